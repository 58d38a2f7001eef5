//! Self-collision settings (scene table `[effects.self_collision]`) and the method's constants,
//! shared by the world's stage (`crate::self_collision`) and the f64 reference.

/// Query radius over collision distance at the default travel: `q = d + 2 T` with the step's
/// relative travel `T = d` ([`SelfCollision::query_factor`] for another travel).
pub const QUERY_FACTOR: f32 = 3.0;

/// Hash cell side over the query radius (Müller's hash uses 1; wider cells were no faster).
pub const CELL_FACTOR: f32 = 1.0;

/// Rest-neighbour skip radius over the query radius: 0.1% more, so that lattice pairs lying
/// exactly at the reach are skipped whatever the rounding.
const REST_SKIP_MARGIN: f32 = 1.001;

/// Rest-neighbour skip radius over the collision distance at the default travel: pairs of one
/// cloth whose rest distance is at most this are never contacts (the query reach
/// `QUERY_FACTOR` times `REST_SKIP_MARGIN`; [`SelfCollision::rest_skip_factor`] for another
/// travel).
pub const REST_SKIP_FACTOR: f32 = QUERY_FACTOR * REST_SKIP_MARGIN;

/// VcCPBD box radius over the collision distance (`r / d`).
pub const BOX_RADIUS: f32 = 1.0;

/// The over-relaxation `ω` of the averaged position correction (`ω c / k`, see
/// `self_collision::response`). A particle in the hollow between partners gets contact
/// normals tilted away from the direction that frees it, and their average is shorter than
/// the move that clears them all; Jacobi over-relaxation by `ω` in `[1, 2]` makes up for it
/// (averaging with successive over-relaxation as in Macklin, Müller, Chentanez & Kim,
/// "Unified Particle Physics for Real-Time Applications"). 1.5 sits in the middle: it keeps
/// a pile's layers apart without the deeper overlaps 2 gives on two stacked cloths.
pub const RELAXATION: f32 = 1.5;

/// Relative travel allowed in one step over the collision distance (`T / d`), by default
/// ([`SelfCollision::travel`]).
pub const TRAVEL_FACTOR: f32 = 1.0;

/// A particle's travel in a step over its speed relative to the mean at the step's start (see
/// [`SelfCollision::travel`]): a particle may speed up by half, relative to the others, from
/// one step to the next before the clamp holds it.
pub const TRAVEL_GROWTH: f32 = 1.5;

/// Least travel over `d` a step (see [`SelfCollision::travel`]): what particles at rest
/// relative to each other may start to move in one step.
pub const TRAVEL_FLOOR: f32 = 0.25;

/// Largest [`SelfCollision::travel`]: the pair lists grow with the cube of the query radius.
pub const MAX_TRAVEL: f32 = 2.0;

/// Collision response (the VcCPBD paper, Shapri, Sulaiman & Bade 2016, compares the three).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Response {
    /// Position projection of the collision constraints (Algorithm 1, Müller et al. 2006).
    Pbd,
    /// Velocity-based: zero the approaching normal velocity and move along the result.
    MovementSpeed,
    /// VcCPBD (Algorithm 2): projection, then the box test and damped-oscillator velocity
    /// correction.
    #[default]
    Vccpbd,
}

impl Response {
    /// The scene spelling: `pbd`, `movement-speed`, `vccpbd`.
    pub fn name(self) -> &'static str {
        match self {
            Response::Pbd => "pbd",
            Response::MovementSpeed => "movement-speed",
            Response::Vccpbd => "vccpbd",
        }
    }
}

/// Self-collision broadphase; both give the same pairs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SelfBroadphase {
    /// Spatial hash rebuilt each step (Müller's "Ten Minute Physics").
    #[default]
    Hash,
    /// AABB tree built once, refitted each step (the VcCPBD paper).
    AabbTree,
}

impl SelfBroadphase {
    /// The scene spelling: `hash`, `aabb-tree`.
    pub fn name(self) -> &'static str {
        match self {
            SelfBroadphase::Hash => "hash",
            SelfBroadphase::AabbTree => "aabb-tree",
        }
    }
}

/// Self-collision settings (scene table `[effects.self_collision]`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SelfCollision {
    /// Collision distance, m; `None` = the smallest `min(thickness, spacing)` of the cloths.
    pub distance: Option<f32>,
    /// Friction `μ` in `[0, 1]`: displacements pulled toward the pair average (Müller's friction).
    pub friction: f32,
    /// The response.
    pub response: Response,
    /// The broadphase.
    pub broadphase: SelfBroadphase,
    /// Measure the paper's "average collision" after every step (the percentage of particles
    /// in penetration, `SelfCollisionStats`). Off by default: the measure has its own
    /// broadphase query, about a quarter of a step of a folded cloth;
    /// `World::measure_self_collision` measures the current state on demand either way.
    #[serde(default)]
    pub measure: bool,
    /// The travel bound `T / d`, in `(0, MAX_TRAVEL]` (default [`TRAVEL_FACTOR`], 1): the speed
    /// clamp lets a particle move at most `travel d` a step relative to the mean velocity of
    /// the free particles, and the pair lists reach at most `(1 + 2 travel) d`. Each step gives
    /// every particle the travel its velocity calls for, up to this bound ([`TRAVEL_GROWTH`]
    /// times its relative speed, at least [`TRAVEL_FLOOR`]; see `self_collision`), so slow
    /// particles list fewer pairs. Lower is cheaper (the lists shrink with the cube of the
    /// reach) and clamps relative motion harder; docs/performance.md measures what it costs
    /// and what it saves on the suite. The rest-neighbour rule follows this bound, not the
    /// particles' travels.
    #[serde(default = "default_travel")]
    pub travel: f32,
}

fn default_travel() -> f32 {
    TRAVEL_FACTOR
}

impl SelfCollision {
    /// Query radius over collision distance, `1 + 2 travel` (the default's is [`QUERY_FACTOR`]).
    pub fn query_factor(&self) -> f32 {
        1.0 + 2.0 * self.travel
    }

    /// Rest-neighbour skip radius over collision distance: the query factor plus 0.1% (see
    /// [`REST_SKIP_FACTOR`]).
    pub fn rest_skip_factor(&self) -> f32 {
        self.query_factor() * REST_SKIP_MARGIN
    }
}

impl Default for SelfCollision {
    fn default() -> Self {
        SelfCollision {
            distance: None,
            friction: 0.3,
            response: Response::default(),
            broadphase: SelfBroadphase::default(),
            measure: false,
            travel: TRAVEL_FACTOR,
        }
    }
}
