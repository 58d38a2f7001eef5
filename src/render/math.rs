//! Small 3-vector helpers used by the rasterizer (plain `[f32; 3]`, no SIMD: the renderer's
//! cost is in the per-pixel loops, which these keep readable).

/// `a + b`.
#[inline]
pub fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a - b`.
#[inline]
pub fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a * s`.
#[inline]
pub fn scale(a: [f32; 3], s: f32) -> [f32; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Dot product.
#[inline]
pub fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product.
#[inline]
pub fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Euclidean length.
#[inline]
pub fn length(a: [f32; 3]) -> f32 {
    dot(a, a).sqrt()
}

/// `a / |a|`, or `None` when `a` is zero or not finite.
#[inline]
pub fn normalize(a: [f32; 3]) -> Option<[f32; 3]> {
    let l = length(a);
    if l > 0.0 && l.is_finite() {
        Some(scale(a, 1.0 / l))
    } else {
        None
    }
}

/// `a / |a|`, or `fallback` when `a` cannot be normalized.
#[inline]
pub fn normalize_or(a: [f32; 3], fallback: [f32; 3]) -> [f32; 3] {
    normalize(a).unwrap_or(fallback)
}

/// True when every component is finite.
#[inline]
pub fn is_finite3(a: [f32; 3]) -> bool {
    a[0].is_finite() && a[1].is_finite() && a[2].is_finite()
}

/// Linear interpolation `a + (b - a) t`.
#[inline]
pub fn lerp3(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    add(a, scale(sub(b, a), t))
}
