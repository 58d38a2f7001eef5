//! Self-collision statistics: the paper's average collision and the stage's phase times (the
//! settings are [`crate::model::self_collision`], the method [`crate::self_collision`]).

/// Relative tolerance of the penetration metric: a pair counts as penetrating when closer than
/// `(1 - PENETRATION_TOLERANCE) d`.
pub const PENETRATION_TOLERANCE: f32 = 0.1;

/// The paper's "average collision" and the time self-collision took.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SelfCollisionStats {
    /// States measured (one after each step but the last, plus on-demand measures).
    pub measured: u64,
    /// Mean percentage of particles in penetration over the measured states.
    pub average_pct: f64,
    /// Largest percentage seen.
    pub max_pct: f64,
    /// Percentage in the last measured state.
    pub last_pct: f64,
    /// Wall time spent in self-collision stages (broadphase, clamp, pairs, correction), s.
    /// The clamp's mean velocity, summed inside the predict pass when there are no
    /// obstacles, counts here too: its chunks' times summed, shared by the threads.
    pub time_s: f64,
    /// Steps that ran self-collision.
    pub steps: u64,
    /// Where the time went.
    pub phases: SelfCollisionPhases,
    /// Steps that ran without self-collision because their pair lists could not be built
    /// (more than [`crate::self_collision::MAX_PAIRS_PER_PARTICLE`] pairs a particle, or
    /// positions the broadphase refuses).
    pub failed_steps: u64,
    /// The error of the last such step.
    pub last_error: Option<String>,
    /// Pairs in the step's lists, averaged over the steps that built them: what each substep's
    /// pair pass tests.
    pub pairs_per_step: f64,
    /// Pairs the pair pass found in contact, averaged over its substeps: what it adds to the
    /// sums and the correction applies.
    pub contacts_per_substep: f64,
    #[serde(skip)]
    sum_pct: f64,
    #[serde(skip)]
    sum_pairs: f64,
    #[serde(skip)]
    listed_steps: u64,
    #[serde(skip)]
    sum_contacts: f64,
    #[serde(skip)]
    passes: u64,
}

/// The self-collision time split by phase, s (summed over the steps; the speed clamp is the
/// rest of [`SelfCollisionStats::time_s`]).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SelfCollisionPhases {
    /// Hash build or tree refit (steps that build the candidate lists).
    pub build_s: f64,
    /// Broadphase query, and the candidates filtered to the step's lists.
    pub query_s: f64,
    /// Step starts in all (`build_s + query_s`, the reuse check and the flat pair list).
    pub step_start_s: f64,
    /// Pair passes of the substeps (contact tests and sums).
    pub pairs_s: f64,
    /// Velocity corrections of the substeps.
    pub correction_s: f64,
    /// Steps that built the candidate lists (ran the broadphase); the others kept them.
    pub rebuilds: u64,
}

impl SelfCollisionStats {
    pub(crate) fn record(&mut self, pct: f64) {
        self.measured += 1;
        self.sum_pct += pct;
        self.average_pct = self.sum_pct / self.measured as f64;
        self.max_pct = self.max_pct.max(pct);
        self.last_pct = pct;
    }

    /// Counts a step's lists of `pairs` pairs.
    pub(crate) fn record_pairs(&mut self, pairs: usize) {
        self.listed_steps += 1;
        self.sum_pairs += pairs as f64;
        self.pairs_per_step = self.sum_pairs / self.listed_steps as f64;
    }

    /// Counts a pair pass that found `contacts` pairs in contact.
    pub(crate) fn record_contacts(&mut self, contacts: usize) {
        self.passes += 1;
        self.sum_contacts += contacts as f64;
        self.contacts_per_substep = self.sum_contacts / self.passes as f64;
    }

    /// Mean self-collision time per step, ms.
    pub fn ms_per_step(&self) -> f64 {
        if self.steps == 0 {
            0.0
        } else {
            self.time_s * 1e3 / self.steps as f64
        }
    }
}
