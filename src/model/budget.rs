//! The memory budget: an estimate of the bytes a world holds, computed from its counts alone
//! (particles, constraints, tethers, triangles, obstacles, named effects), and the limit it
//! must fit in, so that a scene too large for the machine is refused with a message instead of
//! being built until the operating system kills the process.
//!
//! **The estimate** ([`MemoryCounts::bytes`]) adds, from the data layout:
//!
//! | per | bytes | what |
//! |---|---|---|
//! | particle (padded to 8) | 100 | 10 `f32` arrays (`x y z px py pz vx vy vz w`), the 6-array step backup, damping rate and factor, self-collision rest position and cloth index, the embedding's previous positions |
//! | particle, while the piece is built | 16 | the builder's position and inverse mass |
//! | distance constraint | 68 | builder edge (20), world input (16), coloured copy `a b rest compliance lambda` (20), strain list (12) |
//! | tether | 36 | builder, input and solver copies of `particle anchor max_len` |
//! | triangle | 12 | three `u32` |
//! | particle × obstacle | 29 | contact slots: point, normal and approach speed (7 `f32`) and a block flag |
//! | with wind: particle, triangle | 20, 24 | force arrays and adjacency start; triangle force and adjacency |
//! | with self-collision: particle | 176 | step-start positions (12), spatial hash (16), candidate lists (up to 24 partners of 4 bytes), near pairs and compact lists (52) |
//! | with a force-based method: particle, constraint | 36, 48 | force, prediction and clamp arrays; the implicit system's entries |
//! | with implicit Euler: particle × log2(particles) | 600 | the sparse Cholesky factor of the `3n × 3n` system in `f64` and its factorisation workspace |
//!
//! The implicit factor's size is not fixed by the layout but by the fill-in of the ordering:
//! for a 2-D grid under nested dissection it grows as `n log n`, and the constant is the one
//! measured at the peak of a factorisation (160 × 160 cloth: about 840 bytes per particle
//! and `log2 n`, of which 290 stay live).
//!
//! The self-collision row is a typical step's; the step's pair lists are capped at
//! `self_collision::MAX_PAIRS_PER_PARTICLE` (128) pairs a particle on average, about 11 kB a particle with
//! every pair in contact, and a state that needs more (a cloth collapsed onto itself) is
//! refused by the step instead of listed.
//!
//! Growth of `Vec`s while pieces are appended is not in the table; `tests/memory_budget.rs`
//! holds the estimate to an allocation measured with a counting allocator (peak and live bytes
//! of a mid-size world built and stepped) within a factor of two.
//!
//! **The limit** ([`MemoryLimit::current`]) is the smaller of the memory the system says is
//! available (`MemAvailable` in `/proc/meminfo`, where that file exists) and the environment
//! variable `WEFT_MEMORY_LIMIT` (bytes, or a number with a `K`, `M` or `G` suffix, powers of
//! 1024). Where neither exists there is no limit. `World::add_cloth`, `World::add_strands` and
//! scene loading (so `weft check` and `weft run`) refuse a piece whose world would exceed it,
//! before allocating anything for it.
//!
//! ```
//! use weft::model::budget::MemoryCounts;
//! let c = MemoryCounts { particles: 1000, constraints: 4000, ..Default::default() };
//! assert_eq!(c.bytes(), 1000 * (100 + 16) + 4000 * 68);
//! ```

use crate::error::{Result, WeftError};

/// Bytes per padded particle, always.
pub const PER_PARTICLE: u64 = 100;
/// Bytes per particle held only while its piece is built.
pub const PER_PARTICLE_BUILD: u64 = 16;
/// Bytes per distance constraint.
pub const PER_CONSTRAINT: u64 = 68;
/// Bytes per tether.
pub const PER_TETHER: u64 = 36;
/// Bytes per triangle.
pub const PER_TRIANGLE: u64 = 12;
/// Bytes per particle and obstacle (contact slots).
pub const PER_PARTICLE_OBSTACLE: u64 = 29;
/// Bytes per particle with wind named.
pub const WIND_PER_PARTICLE: u64 = 20;
/// Bytes per triangle with wind named.
pub const WIND_PER_TRIANGLE: u64 = 24;
/// Bytes per particle with self-collision named.
pub const SELF_COLLISION_PER_PARTICLE: u64 = 176;
/// Bytes per particle with a force-based method.
pub const FORCE_PER_PARTICLE: u64 = 36;
/// Bytes per constraint with a force-based method.
pub const FORCE_PER_CONSTRAINT: u64 = 48;
/// Bytes per particle and `log2` of the particle count with implicit Euler.
pub const IMPLICIT_PER_PARTICLE_LOG2: u64 = 600;

/// What the estimate is computed from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryCounts {
    /// Particles (padding to a multiple of eight is added by the estimate).
    pub particles: u64,
    /// Distance constraints.
    pub constraints: u64,
    /// Tethers.
    pub tethers: u64,
    /// Triangles.
    pub triangles: u64,
    /// Obstacles.
    pub obstacles: u64,
    /// Wind is named.
    pub wind: bool,
    /// Self-collision is named.
    pub self_collision: bool,
    /// The method is force-based (symplectic Euler, leapfrog, implicit Euler).
    pub force_method: bool,
    /// The method is implicit Euler (a sparse factorisation).
    pub implicit: bool,
}

impl MemoryCounts {
    /// The estimated bytes (saturating: absurd counts give `u64::MAX`, never an overflow).
    pub fn bytes(&self) -> u64 {
        let n = self.particles.saturating_add(7) / 8 * 8;
        let mut per_particle = PER_PARTICLE + PER_PARTICLE_BUILD;
        per_particle = per_particle.saturating_add(self.obstacles.saturating_mul(PER_PARTICLE_OBSTACLE));
        let mut per_triangle = PER_TRIANGLE;
        let mut per_constraint = PER_CONSTRAINT;
        if self.wind {
            per_particle += WIND_PER_PARTICLE;
            per_triangle += WIND_PER_TRIANGLE;
        }
        if self.self_collision {
            per_particle += SELF_COLLISION_PER_PARTICLE;
        }
        if self.force_method {
            per_particle += FORCE_PER_PARTICLE;
            per_constraint += FORCE_PER_CONSTRAINT;
        }
        if self.implicit {
            let log2 = 64 - n.leading_zeros() as u64;
            per_particle = per_particle.saturating_add(IMPLICIT_PER_PARTICLE_LOG2 * log2);
        }
        n.saturating_mul(per_particle)
            .saturating_add(self.constraints.saturating_mul(per_constraint))
            .saturating_add(self.tethers.saturating_mul(PER_TETHER))
            .saturating_add(self.triangles.saturating_mul(per_triangle))
    }

    /// The counts of two sets of pieces together (flags of either).
    pub fn plus(&self, o: &MemoryCounts) -> MemoryCounts {
        MemoryCounts {
            particles: self.particles.saturating_add(o.particles),
            constraints: self.constraints.saturating_add(o.constraints),
            tethers: self.tethers.saturating_add(o.tethers),
            triangles: self.triangles.saturating_add(o.triangles),
            obstacles: self.obstacles.saturating_add(o.obstacles),
            wind: self.wind || o.wind,
            self_collision: self.self_collision || o.self_collision,
            force_method: self.force_method || o.force_method,
            implicit: self.implicit || o.implicit,
        }
    }

    /// Refuses counts whose estimate exceeds the current limit ([`MemoryLimit::current`]).
    pub fn check(&self) -> Result<()> {
        match MemoryLimit::current()? {
            Some(limit) => limit.admit(self.bytes()),
            None => Ok(()),
        }
    }
}

/// A memory limit and where it comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryLimit {
    /// Bytes.
    pub bytes: u64,
    /// Where the figure comes from (`MemAvailable` or `WEFT_MEMORY_LIMIT`).
    pub source: &'static str,
}

impl MemoryLimit {
    /// The smaller of `MemAvailable` and `WEFT_MEMORY_LIMIT`; `None` when neither exists.
    /// A `WEFT_MEMORY_LIMIT` that is not a size is an error.
    pub fn current() -> Result<Option<MemoryLimit>> {
        let user = match std::env::var("WEFT_MEMORY_LIMIT") {
            Ok(s) => Some(MemoryLimit {
                bytes: parse_size(&s).ok_or_else(|| {
                    WeftError::param(
                        "WEFT_MEMORY_LIMIT",
                        &s,
                        "must be a size in bytes, optionally with a K, M or G suffix",
                    )
                })?,
                source: "WEFT_MEMORY_LIMIT",
            }),
            Err(_) => None,
        };
        let system = std::fs::read_to_string("/proc/meminfo")
            .ok()
            .and_then(|t| mem_available(&t))
            .map(|bytes| MemoryLimit {
                bytes,
                source: "MemAvailable in /proc/meminfo",
            });
        Ok(match (user, system) {
            (Some(u), Some(s)) => Some(if u.bytes <= s.bytes { u } else { s }),
            (u, s) => u.or(s),
        })
    }

    /// Refuses `estimate` bytes above the limit, naming both.
    pub fn admit(&self, estimate: u64) -> Result<()> {
        if estimate > self.bytes {
            return Err(WeftError::param(
                "memory",
                format!("~{} estimated", human_bytes(estimate)),
                format!(
                    "more than the {} available ({}); make the scene smaller or raise WEFT_MEMORY_LIMIT within what the machine has",
                    human_bytes(self.bytes),
                    self.source
                ),
            ));
        }
        Ok(())
    }
}

/// `MemAvailable` of `/proc/meminfo` text, in bytes.
pub fn mem_available(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let mut it = line["MemAvailable:".len()..].split_whitespace();
    let v: u64 = it.next()?.parse().ok()?;
    match it.next() {
        Some("kB") => v.checked_mul(1024),
        None => Some(v),
        _ => None,
    }
}

/// Parses `123`, `64K`, `512M`, `2G` (powers of 1024; a trailing `B` or `iB` is allowed).
pub fn parse_size(s: &str) -> Option<u64> {
    let t = s.trim();
    let t = t.strip_suffix("iB").or_else(|| t.strip_suffix('B')).unwrap_or(t);
    let (num, mult) = match t.chars().last()? {
        'k' | 'K' => (&t[..t.len() - 1], 1u64 << 10),
        'm' | 'M' => (&t[..t.len() - 1], 1 << 20),
        'g' | 'G' => (&t[..t.len() - 1], 1 << 30),
        't' | 'T' => (&t[..t.len() - 1], 1 << 40),
        _ => (t, 1),
    };
    num.trim().parse::<u64>().ok()?.checked_mul(mult)
}

/// `1.5 GiB`, `12.0 MiB`, ...
pub fn human_bytes(b: u64) -> String {
    match b {
        b if b >= 1 << 30 => format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64),
        b if b >= 1 << 20 => format!("{:.1} MiB", b as f64 / (1u64 << 20) as f64),
        b if b >= 1 << 10 => format!("{:.1} KiB", b as f64 / 1024.0),
        b => format!("{b} B"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_meminfo_parse() {
        assert_eq!(parse_size("123"), Some(123));
        assert_eq!(parse_size("64K"), Some(64 << 10));
        assert_eq!(parse_size("512MiB"), Some(512 << 20));
        assert_eq!(parse_size(" 2G "), Some(2 << 30));
        assert_eq!(parse_size("lots"), None);
        assert_eq!(parse_size(""), None);
        assert_eq!(parse_size("99999999999999999999G"), None);
        let info = "MemTotal:       16000000 kB\nMemFree: 1 kB\nMemAvailable:    8000000 kB\n";
        assert_eq!(mem_available(info), Some(8_000_000 * 1024));
        assert_eq!(mem_available("MemTotal: 5 kB\n"), None);
    }

    #[test]
    fn limit_names_estimate_and_limit() {
        let l = MemoryLimit {
            bytes: 1 << 30,
            source: "WEFT_MEMORY_LIMIT",
        };
        assert!(l.admit(1 << 30).is_ok());
        let e = l.admit(3 << 30).unwrap_err().to_string();
        assert!(
            e.contains("3.0 GiB") && e.contains("1.0 GiB") && e.contains("WEFT_MEMORY_LIMIT"),
            "{e}"
        );
        let huge = MemoryCounts {
            particles: u64::MAX,
            constraints: u64::MAX,
            ..Default::default()
        };
        assert_eq!(huge.bytes(), u64::MAX);
    }
}
