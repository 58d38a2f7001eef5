//! The pinhole camera and its perspective projection.
//!
//! A camera at `eye` looking at `target` gets an orthonormal basis: forward
//! `f = (target - eye)/|target - eye|`, right `r = f × up / |f × up|`, true up `u = r × f`.
//! A world point `p` has view coordinates `x = r·(p - eye)`, `y = u·(p - eye)`,
//! `z = f·(p - eye)` (depth, positive in front), and lands on the pixel
//! `(W/2 + φ x/z, H/2 - φ y/z)` with focal length `φ = (H/2) / tan(fov_y/2)` in pixels.
//! Because screen position is `x/z`, attributes are interpolated across a triangle by
//! interpolating `a/z` and `1/z` linearly in screen space (perspective-correct interpolation).

use super::math::{cross, dot, is_finite3, length, normalize, scale, sub};
use crate::{Result, WeftError};

/// A perspective camera: position, point looked at, up hint and vertical field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Camera position in world space.
    pub eye: [f32; 3],
    /// Point the camera looks at.
    pub target: [f32; 3],
    /// Up hint; it need not be perpendicular to the view direction. If it is parallel to it,
    /// another up is chosen so that a straight-down view still works.
    pub up: [f32; 3],
    /// Vertical field of view in degrees, in (0, 179).
    pub fov_y_deg: f32,
}

/// Field of view used by [`Camera::framing`].
const FRAMING_FOV_DEG: f32 = 35.0;
/// Fraction of the half-field that the box may fill when framed.
const FRAMING_FILL: f32 = 0.88;

impl Camera {
    /// A pleasant three-quarter view from the front (+z), above (+y is up) and a little to the
    /// right, at a distance where the whole box fits a square image.
    pub fn framing(min: [f32; 3], max: [f32; 3]) -> Camera {
        Camera::framing_for_aspect(min, max, 1.0)
    }

    /// Like [`Camera::framing`], for an image of `aspect = width / height`, so that the box
    /// fits horizontally too. Non-finite boxes fall back to the unit cube around the origin.
    pub fn framing_for_aspect(min: [f32; 3], max: [f32; 3], aspect: f32) -> Camera {
        let (min, max) = if is_finite3(min) && is_finite3(max) {
            (min, max)
        } else {
            ([-0.5; 3], [0.5; 3])
        };
        let aspect = if aspect.is_finite() && aspect > 0.0 { aspect } else { 1.0 };
        let target = scale([min[0] + max[0], min[1] + max[1], min[2] + max[2]], 0.5);
        let extent = length(sub(max, min)).max(1e-3);
        let up = [0.0, 1.0, 0.0];
        // Direction from the target toward the eye: front, above, slightly right.
        let back = normalize([0.55, 0.6, 1.0]).unwrap_or([0.0, 0.0, 1.0]);
        let right = normalize(cross(scale(back, -1.0), up)).unwrap_or([1.0, 0.0, 0.0]);
        let true_up = cross(right, scale(back, -1.0));
        let tan_y = (FRAMING_FOV_DEG.to_radians() * 0.5).tan() * FRAMING_FILL;
        let tan_x = tan_y * aspect;
        // Smallest eye distance d with every box corner inside the view:
        // |lateral| <= tan * depth, where depth = d - back·offset.
        let mut dist = 0.0f32;
        for k in 0..8 {
            let c = [
                if k & 1 == 0 { min[0] } else { max[0] },
                if k & 2 == 0 { min[1] } else { max[1] },
                if k & 4 == 0 { min[2] } else { max[2] },
            ];
            let o = sub(c, target);
            let along = dot(o, back);
            dist = dist.max(dot(o, right).abs() / tan_x + along);
            dist = dist.max(dot(o, true_up).abs() / tan_y + along);
        }
        let dist = dist.max(extent * 0.6);
        Camera {
            eye: [target[0] + back[0] * dist, target[1] + back[1] * dist, target[2] + back[2] * dist],
            target,
            up,
            fov_y_deg: FRAMING_FOV_DEG,
        }
    }

    /// Checks the camera and builds its view for an image of `width` x `height` pixels.
    pub(crate) fn view(&self, width: u32, height: u32) -> Result<View> {
        let bad = |name: &str, v: [f32; 3]| WeftError::param(name, format!("{v:?}"), "every component must be a finite number");
        for (name, v) in [("camera.eye", self.eye), ("camera.target", self.target), ("camera.up", self.up)] {
            if !is_finite3(v) {
                return Err(bad(name, v));
            }
        }
        if !(self.fov_y_deg.is_finite() && self.fov_y_deg > 0.0 && self.fov_y_deg < 179.0) {
            return Err(WeftError::param(
                "camera.fov_y_deg",
                self.fov_y_deg,
                "must be a finite angle between 0 and 179 degrees",
            ));
        }
        let to_target = sub(self.target, self.eye);
        let distance = length(to_target);
        let forward = normalize(to_target)
            .ok_or_else(|| WeftError::param("camera.target", format!("{:?}", self.target), "must differ from camera.eye"))?;
        let right = [self.up, [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]
            .iter()
            .find_map(|&u| {
                let c = cross(forward, u);
                (length(c) > 1e-4 * length(u).max(1e-30)).then(|| normalize(c))?
            })
            .unwrap_or([1.0, 0.0, 0.0]);
        let up = cross(right, forward);
        let focal = 0.5 * height as f32 / (self.fov_y_deg.to_radians() * 0.5).tan();
        Ok(View {
            eye: self.eye,
            right,
            up,
            forward,
            focal,
            cx: 0.5 * width as f32,
            cy: 0.5 * height as f32,
            near: (distance * 1e-3).max(1e-5),
        })
    }
}

/// A checked camera, ready to project: basis, focal length in pixels, image centre, near plane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct View {
    /// Camera position.
    pub eye: [f32; 3],
    /// Unit right vector.
    pub right: [f32; 3],
    /// Unit up vector (perpendicular to `forward`).
    pub up: [f32; 3],
    /// Unit viewing direction.
    pub forward: [f32; 3],
    /// Focal length in pixels.
    pub focal: f32,
    /// Image centre, x.
    pub cx: f32,
    /// Image centre, y.
    pub cy: f32,
    /// Near clipping distance.
    pub near: f32,
}

impl View {
    /// World point to view coordinates `(x, y, z)`, z = depth along the view direction.
    #[inline]
    pub fn view_coords(&self, p: [f32; 3]) -> [f32; 3] {
        let d = sub(p, self.eye);
        [dot(d, self.right), dot(d, self.up), dot(d, self.forward)]
    }

    /// View coordinates (with `z >= near`) to screen `(sx, sy, 1/z)`.
    #[inline]
    pub fn project(&self, v: [f32; 3]) -> [f32; 3] {
        let iz = 1.0 / v[2];
        [self.cx + self.focal * v[0] * iz, self.cy - self.focal * v[1] * iz, iz]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_puts_every_corner_inside_the_image() {
        let (min, max) = ([-2.0, 0.0, -1.0], [3.0, 1.5, 0.5]);
        for aspect in [0.5f32, 1.0, 2.0] {
            let (w, h) = ((200.0 * aspect) as u32, 200u32);
            let view = Camera::framing_for_aspect(min, max, aspect).view(w, h).unwrap();
            for k in 0..8 {
                let c = [
                    if k & 1 == 0 { min[0] } else { max[0] },
                    if k & 2 == 0 { min[1] } else { max[1] },
                    if k & 4 == 0 { min[2] } else { max[2] },
                ];
                let v = view.view_coords(c);
                assert!(v[2] > view.near);
                let s = view.project(v);
                assert!(s[0] >= 0.0 && s[0] <= w as f32, "x {s:?} aspect {aspect}");
                assert!(s[1] >= 0.0 && s[1] <= h as f32, "y {s:?} aspect {aspect}");
            }
        }
    }

    #[test]
    fn framing_looks_from_front_above() {
        let cam = Camera::framing([-1.0; 3], [1.0; 3]);
        assert!(cam.eye[1] > cam.target[1] && cam.eye[2] > cam.target[2]);
        let cam = Camera::framing([f32::NAN; 3], [1.0; 3]);
        assert!(is_finite3(cam.eye));
    }

    #[test]
    fn bad_cameras_are_errors_and_straight_down_works() {
        let mut cam = Camera::framing([-1.0; 3], [1.0; 3]);
        cam.fov_y_deg = 0.0;
        assert!(cam.view(10, 10).is_err());
        cam.fov_y_deg = 40.0;
        cam.eye = cam.target;
        assert!(cam.view(10, 10).is_err());
        cam.eye = [0.0, f32::INFINITY, 0.0];
        assert!(cam.view(10, 10).is_err());
        let down = Camera {
            eye: [0.0, 5.0, 0.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 40.0,
        };
        let view = down.view(10, 10).unwrap();
        assert!(is_finite3(view.right) && is_finite3(view.up));
        let s = view.project(view.view_coords([0.0; 3]));
        assert!((s[0] - 5.0).abs() < 1e-4 && (s[1] - 5.0).abs() < 1e-4);
    }
}
