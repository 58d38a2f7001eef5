//! Which particles of a bucket are *members* of its home cell (module `cells`): in the home
//! cell, with the search box inside the 27 cells around it, and (travels attached) of travel
//! at most the members' (`SpatialHash::attach_travel`). One particle at a time (the scalar
//! twin) or eight at a time in lanes.

use crate::data::lanes::{load, F32s, LANES};
use crate::self_collision::hash::cells::SpatialHash;
use crate::self_collision::neighbours::search_radius;

impl SpatialHash {
    /// The cell side for the self-collision query within `max_dist`: a hair wider than the
    /// query's search radius, so that a particle on a cell's lower face has its search box
    /// inside the 27 cells around it, as one inside the cell has. With cells exactly
    /// `max_dist` wide, the box of a particle on a face reaches one cell further (the radius
    /// exceeds `max_dist` by a rounding margin), and a flat cloth lying in the plane of a face
    /// (`z = 0` before anything moves it off) would scan whole boxes instead of half shells.
    /// (Far from the origin, where a coordinate's rounding exceeds the margin, a particle on a
    /// face can still fail the test: correct, only slower.)
    pub fn member_spacing(max_dist: f32) -> f32 {
        search_radius(max_dist) * (1.0 + 1.0 / 1_048_576.0)
    }

    /// Integer cell of the particle in slot `k`.
    #[inline(always)]
    pub(super) fn cell_of_slot(&self, k: usize) -> [i32; 3] {
        [self.coord(self.sx[k]), self.coord(self.sy[k]), self.coord(self.sz[k])]
    }

    /// Whether the particle in slot `k` lies in cell `home` with its search box (radius `r`)
    /// inside the 27 cells around it and is no faster than the members. Cell coordinates below
    /// `2^22` in magnitude are compared as `f32` (integers there are exact, so this equals the
    /// integer test), others as `i64`.
    #[inline(always)]
    pub(super) fn member(&self, k: usize, home: [i32; 3], r: f32) -> bool {
        let rc = &self.rest;
        if rc.d.is_some() && rc.travel[k] > rc.cell {
            return false;
        }
        self.member_box(k, home, r)
    }

    /// The cell and box conditions of [`SpatialHash::member`].
    #[inline(always)]
    fn member_box(&self, k: usize, home: [i32; 3], r: f32) -> bool {
        let p = [self.sx[k], self.sy[k], self.sz[k]];
        let inv = self.inv_spacing;
        let mut ok = true;
        for a in 0..3 {
            let c = (p[a] * inv).floor();
            if c.is_nan() || c.abs() >= 4_194_304.0 {
                return self.member_wide(p, home, r);
            }
            let lo = ((p[a] - r) * inv).floor();
            let hi = ((p[a] + r) * inv).floor();
            ok &= c as i32 == home[a] && lo >= c - 1.0 && hi <= c + 1.0;
        }
        ok
    }

    /// [`SpatialHash::member`] of slots `k..min(k + 8, e)` at once, as bits (bit `l` for slot
    /// `k + l`): the same comparisons in `f32` lanes, a lane whose cell is NaN or beyond
    /// `2^22` decided by the scalar test. The slot arrays are padded by a lane group, so the
    /// loads stay inside them. The scalar test costs about a hundred instructions a particle
    /// (three floors, three saturating conversions and their range checks an axis).
    #[inline(always)]
    pub(super) fn member_lanes(&self, k: usize, e: usize, home: [i32; 3], r: f32) -> u32 {
        let inv = F32s::splat(self.inv_spacing);
        let (rv, one) = (F32s::splat(r), F32s::ONE);
        let big = F32s::splat(4_194_304.0);
        let mut ok = F32s::splat(f32::from_bits(u32::MAX));
        let mut odd = F32s::ZERO;
        for (a, coords) in [&self.sx, &self.sy, &self.sz].into_iter().enumerate() {
            let p = load(coords, k);
            let c = (p * inv).floor();
            let lo = ((p - rv) * inv).floor();
            let hi = ((p + rv) * inv).floor();
            // NaN fails `abs < big` too, so both go to the scalar test.
            odd |= !c.abs().simd_lt(big);
            ok &= c.simd_eq(F32s::splat(home[a] as f32)) & lo.simd_ge(c - one) & hi.simd_le(c + one);
        }
        let rc = &self.rest;
        if rc.d.is_some() {
            ok &= load(&rc.travel, k).simd_le(F32s::splat(rc.cell));
        }
        let live = if e - k < LANES { (1u32 << (e - k)) - 1 } else { 0xff };
        let mut bits = ok.to_bitmask() & live;
        let mut odd = odd.to_bitmask() & live;
        while odd != 0 {
            let l = odd.trailing_zeros();
            bits &= !(1 << l);
            if self.member(k + l as usize, home, r) {
                bits |= 1 << l;
            }
            odd &= odd - 1;
        }
        bits
    }

    /// [`SpatialHash::member`] for far coordinates, on saturated integer cells.
    #[cold]
    fn member_wide(&self, p: [f32; 3], home: [i32; 3], r: f32) -> bool {
        (0..3).all(|a| {
            let c = i64::from(home[a]);
            let lo = i64::from(self.coord((p[a] - r).max(-f32::MAX)));
            let hi = i64::from(self.coord((p[a] + r).min(f32::MAX)));
            i64::from(self.coord(p[a])) == c && lo >= c - 1 && hi <= c + 1
        })
    }
}
