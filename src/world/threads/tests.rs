use super::*;
use crate::model::self_collision::SelfCollision;
use crate::{ClothDesc, Effects, SolverParams};

fn shape(particles: usize) -> Shape {
    Shape {
        particles,
        substeps: 4,
        iterations: 1,
        method: Method::Xpbd,
        self_collision: false,
        obstacles: 0,
    }
}

/// Runs one trial with step times `pool` and `caller` (seconds) from step `steps` on; returns
/// the sides the steps ran on.
fn trial(c: &mut ThreadChoice, s: Shape, steps: &mut u64, pool: f64, caller: f64) -> Vec<bool> {
    let mut sides = Vec::new();
    for _ in 0..TRIAL_STEPS {
        c.begin(s, *steps);
        let side = c.caller_next();
        sides.push(side);
        *steps += 1;
        c.start = None;
        c.record(if side { caller } else { pool }, *steps);
    }
    sides
}

#[test]
fn a_trial_alternates_and_keeps_the_faster_side() {
    let mut c = ThreadChoice::default();
    let mut steps = 0;
    let sides = trial(&mut c, shape(100), &mut steps, 2e-3, 1e-3);
    let want: Vec<bool> = (0..TRIAL_STEPS).map(|k| (k / TRIAL_BLOCK) % 2 == 1).collect();
    assert_eq!(sides, want);
    assert!(c.caller_next());
    assert_eq!(
        c.report(),
        Some(ThreadChoiceReport {
            caller_thread: true,
            pool_ms: 2.0,
            caller_ms: 1.0
        })
    );
    // The other way round on a new shape: a new trial, the pool kept.
    trial(&mut c, shape(200), &mut steps, 1e-3, 2e-3);
    assert!(!c.caller_next());
    assert!(!c.report().unwrap().caller_thread);
}

#[test]
fn the_warm_up_steps_of_a_block_are_not_counted() {
    let mut c = ThreadChoice::default();
    let s = shape(100);
    let mut steps = 0;
    // Very slow first pool steps and fast first caller steps (workers waking up, cold
    // caches): the rest of the trial says the pool is faster.
    for k in 0..TRIAL_STEPS {
        c.begin(s, steps);
        steps += 1;
        let t = match (k % TRIAL_BLOCK < TRIAL_WARM_UP, c.caller_next()) {
            (true, false) => 1.0,
            (true, true) => 1e-6,
            (_, true) => 2e-3,
            (_, false) => 1e-3,
        };
        c.record(t, steps);
    }
    assert_eq!(c.report().map(|r| r.caller_thread), Some(false));
}

#[test]
fn the_choice_holds_until_it_is_stale_or_the_shape_changes() {
    let mut c = ThreadChoice::default();
    let s = shape(100);
    let mut steps = 0;
    // The first choice is confirmed by a second trial after CONFIRM_AFTER steps, later clear
    // ones last RETRY_AFTER steps, close ones CONFIRM_AFTER again.
    let close = 1e-3 * (CLEAR_MARGIN - 0.01);
    for (life, pool) in [
        (CONFIRM_AFTER, 2e-3),
        (RETRY_AFTER, 2e-3),
        (CONFIRM_AFTER, close),
        (RETRY_AFTER, 2e-3),
    ] {
        trial(&mut c, s, &mut steps, pool, 1e-3);
        let chosen = steps;
        // Chosen steps do not change the choice, whatever they take.
        while steps < chosen + life {
            c.begin(s, steps);
            assert!(c.caller_next(), "step {steps}");
            steps += 1;
            c.record(1.0, steps);
        }
        // Stale: a new trial starts with the pool; the last outcome is still reported.
        let last = c.report().expect("a trial has finished");
        assert_eq!(last.pool_ms, pool * 1e3);
        c.begin(s, steps);
        assert!(!c.caller_next());
        assert_eq!(c.report(), Some(last));
    }
    // A shape change mid-choice starts one too, and forgets the old shape's outcome.
    let mut c = ThreadChoice::default();
    let mut steps = 0;
    trial(&mut c, s, &mut steps, 2e-3, 1e-3);
    c.begin(Shape { substeps: 8, ..s }, steps);
    assert!(!c.caller_next());
    assert_eq!(c.report(), None);
}

/// A trial that reverses the one before it is confirmed after [`CONFIRM_AFTER`] steps, like a
/// first trial: one trial that caught the machine busy does not decide [`RETRY_AFTER`] steps.
#[test]
fn a_reversed_choice_is_confirmed_soon() {
    let mut c = ThreadChoice::default();
    let s = shape(100);
    let mut steps = 0;
    // (pool, caller) step times of each trial, and how long its clear choice lasts.
    for (life, pool, caller) in [
        (CONFIRM_AFTER, 2e-3, 1e-3),
        (RETRY_AFTER, 2e-3, 1e-3),
        (CONFIRM_AFTER, 1e-3, 2e-3),
        (RETRY_AFTER, 1e-3, 2e-3),
        (CONFIRM_AFTER, 2e-3, 1e-3),
    ] {
        trial(&mut c, s, &mut steps, pool, caller);
        assert_eq!(c.settled(), life == RETRY_AFTER, "step {steps}");
        let chosen = steps;
        let caller_side = caller < pool;
        while steps < chosen + life {
            c.begin(s, steps);
            assert_eq!(c.caller_next(), caller_side, "step {steps}");
            steps += 1;
            c.record(1.0, steps);
        }
        // Stale: the next trial starts with a block in the pool.
        c.begin(s, steps);
        assert!(!c.caller_next() && c.trial == 0 && !c.settled(), "step {steps}");
    }
}

/// A 40 x 40 cloth held by its middle row, its halves falling and folding, self-collision on.
fn world(threads: usize) -> World {
    let params = SolverParams {
        threads,
        substeps: 4,
        ..Default::default()
    };
    let mut w = World::new(params, Effects::gravity()).unwrap();
    w.add_cloth(&ClothDesc {
        rows: 40,
        cols: 40,
        spacing: 0.01,
        origin: [-0.2, 0.5, -0.2],
        u: [1.0, 0.0, 0.0],
        v: [0.0, 0.0, 1.0],
        pins: vec![crate::model::cloth::PinSpec::Row(20)],
        ..Default::default()
    })
    .unwrap();
    w.set_self_collision(Some(SelfCollision::default())).unwrap();
    w
}

#[test]
fn threads_zero_switches_sides_and_keeps_the_bits_of_one_thread() {
    let mut auto = world(0);
    let mut one = world(1);
    let mut sides = Vec::new();
    for step in 0..2 * TRIAL_STEPS {
        auto.begin_thread_choice();
        sides.push(auto.on_caller_thread());
        auto.thread_choice.start = None;
        auto.step(1.0 / 60.0).unwrap();
        one.step(1.0 / 60.0).unwrap();
        assert_eq!(auto.state_bits(), one.state_bits(), "step {step}");
    }
    // The trial ran steps on both sides, then chose one.
    let trial = &sides[..TRIAL_STEPS as usize];
    assert!(trial.contains(&true) && trial.contains(&false), "{sides:?}");
    let r = auto.thread_choice().expect("the trial is over");
    assert!(r.pool_ms > 0.0 && r.caller_ms > 0.0);
    assert!(sides[TRIAL_STEPS as usize..].iter().all(|&s| s == r.caller_thread), "{sides:?}");
    assert_eq!(one.thread_choice(), None, "threads = 1 measures nothing");
}
