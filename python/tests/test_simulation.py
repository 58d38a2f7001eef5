"""Behaviour of a stepped world: settling, obstacles, determinism, scenes, snapshots."""

import sys
import threading

import numpy as np
import pytest

import weft


def hanging_world(threads=0, backend="simd", rows=16, cols=16):
    """A sheet starting horizontal (rows along +z), pinned at two corners: it swings down."""
    w = weft.World(threads=threads, backend=backend)
    w.add_cloth(weft.ClothDesc(rows=rows, cols=cols, spacing=0.05, v=(0, 0, 1), fabric="basic", pins=["first-row-corners"]))
    return w


def test_hanging_cloth_settles_and_pins_stay():
    w = hanging_world()
    pins = [0, 15]
    x0 = w.positions()[pins]
    speeds = []
    for _ in range(600):  # 10 s
        w.step()
        speeds.append(np.linalg.norm(w.velocities(), axis=1).max())
    early, late = max(speeds[:60]), max(speeds[-30:])
    assert early > 2.0, early  # it fell and swung
    assert late < 0.05 * early, (early, late)  # and came to rest (damping 0.8 / s)
    np.testing.assert_array_equal(w.positions()[pins], x0)
    np.testing.assert_array_equal(w.velocities()[pins], 0.0)
    # It hangs below its pins.
    assert w.positions()[:, 1].max() <= x0[:, 1].max() + 1e-6
    assert w.positions()[:, 1].min() < x0[:, 1].min() - 0.3
    assert w.steps == 600 and abs(w.time - 10.0) < 1e-3


@pytest.mark.parametrize("steps", [40])
def test_same_bits_on_any_thread_count_and_backend(steps):
    # threads=0 runs its first steps in the pool and on the calling thread in turn.
    worlds = [hanging_world(threads=1), hanging_world(threads=2), hanging_world(threads=0), hanging_world(backend="scalar")]
    for w in worlds:
        w.add_sphere((0.4, 0.3, 0.1), 0.2)
        w.set_self_collision(weft.SelfCollision())
        for _ in range(steps):
            w.step()
    ref = worlds[0]
    assert np.abs(ref.positions() - hanging_world().positions()).max() > 0.1  # it moved
    # A tighter travel bound clamps the swing: other positions, still the same on any thread count.
    tight = [hanging_world(threads=t) for t in (1, 2)]
    for w in tight:
        w.add_sphere((0.4, 0.3, 0.1), 0.2)
        w.set_self_collision(weft.SelfCollision(travel=0.1))
        for _ in range(steps):
            w.step()
    np.testing.assert_array_equal(tight[0].positions(), tight[1].positions())
    assert np.abs(tight[0].positions() - ref.positions()).max() > 1e-4
    for w in worlds[1:]:
        np.testing.assert_array_equal(w.positions(), ref.positions())
        np.testing.assert_array_equal(w.velocities(), ref.velocities())


def test_thread_choice_after_the_trial():
    w, one = hanging_world(threads=0), hanging_world(threads=1)
    # None until the trial (some tens of steps) has run both sides.
    took = next((k for k in range(200) if w.thread_choice is not None or w.step()), None)
    assert took is not None and took > 2, took
    one.step()
    c = w.thread_choice
    assert set(c) == {"caller_thread", "pool_ms", "caller_ms"}
    assert isinstance(c["caller_thread"], bool) and c["pool_ms"] > 0 and c["caller_ms"] > 0
    assert one.thread_choice is None


def test_step_releases_the_gil():
    """Another Python thread runs while this one is inside step().

    The spinner counts only while the flag `inside` is set, just around the call. With the
    lock held through the step it could run there only if the interpreter forced a switch in
    the few bytecodes before the call, which a long switch interval rules out.
    """
    w = hanging_world(rows=64, cols=64)
    state = {"inside": False, "seen": 0, "stop": False}

    def spin():
        while not state["stop"]:
            if state["inside"]:
                state["seen"] += 1

    old = sys.getswitchinterval()
    sys.setswitchinterval(0.05)
    t = threading.Thread(target=spin)
    t.start()
    try:
        for _ in range(10):
            state["inside"] = True
            w.step()
            state["inside"] = False
    finally:
        state["stop"] = True
        t.join()
        sys.setswitchinterval(old)
    assert state["seen"] > 0


def flat_sheet(world, height):
    world.add_cloth(weft.ClothDesc(rows=12, cols=12, spacing=0.05, origin=(-0.275, height, -0.275), u=(1, 0, 0), v=(0, 0, 1), pins=[]))


@pytest.mark.parametrize(
    "add",
    [
        lambda w: w.add_plane((0, 0, 0), (0, 2, 0)),
        lambda w: w.add_sphere((0, -1.0, 0), 1.0),
        lambda w: w.add_capsule((-1, -0.5, 0), (1, -0.5, 0), 0.5),
        lambda w: w.add_box((0, -0.5, 0), (1, 0.5, 1)),
        lambda w: w.add_box((0, -0.5, 0), (1, 0.5, 1), rotation=(0, 30, 0)),
        lambda w: w.add_mesh(
            np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], dtype=np.float64),
            np.array([[0, 2, 1], [0, 3, 2]]),
        ),
        lambda w: w.add_mesh(
            np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]]),
            [[0, 2, 1], [0, 3, 2]],
            broadphase="bvh",
            face_memory=True,
        ),
    ],
    ids=["plane", "sphere", "capsule", "box", "rotated-box", "mesh", "mesh-bvh"],
)
def test_obstacles_stop_a_falling_sheet(add):
    """Each obstacle's top is at y = 0 under the sheet's centre; the sheet lands on it."""
    w = weft.World(friction=0.5)
    flat_sheet(w, 0.3)
    with pytest.warns(UserWarning, match="not closed") if "mesh" in repr(add.__code__.co_names) else _nothing():
        assert add(w) == 0
    assert w.obstacle_count == 1
    for _ in range(90):
        w.step()
    x = w.positions()
    centre = np.argmin(np.linalg.norm(x[:, [0, 2]], axis=1))
    assert x[centre, 1] > -0.005, x[centre, 1]
    assert x[centre, 1] < 0.05  # it fell onto the obstacle
    free = weft.World()
    flat_sheet(free, 0.3)
    for _ in range(90):
        free.step()
    assert free.positions()[:, 1].max() < -0.5  # without it the sheet falls through


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *a):
        return False


def test_from_scene_hanging(scenes):
    w = weft.World.from_scene(scenes / "hanging.toml")
    assert w.particle_count == 40 * 40
    assert abs(w.dt - 0.016666667) < 1e-9
    x0 = w.positions()
    for _ in range(30):
        w.step()
    x = w.positions()
    assert x[:, 1].min() < x0[:, 1].min() - 0.05  # swinging down
    np.testing.assert_array_equal(x[[0, 39]], x0[[0, 39]])  # first-row corners pinned
    # The same scene text through from_scene_text gives the same bits.
    w2 = weft.World.from_scene_text((scenes / "hanging.toml").read_text(), "hanging.toml")
    for _ in range(30):
        w2.step()
    np.testing.assert_array_equal(w2.positions(), x)


def test_snapshot_restore_round_trip():
    w = hanging_world()
    for _ in range(10):
        w.step()
    snap = w.snapshot()
    assert snap.steps == 10 and snap.particle_count == 256
    x_snap = w.positions()
    for _ in range(25):
        w.step()
    first = (w.positions(), w.velocities(), w.time)
    w.restore(snap)
    np.testing.assert_array_equal(w.positions(), x_snap)
    assert w.steps == 10
    for _ in range(25):
        w.step()
    np.testing.assert_array_equal(w.positions(), first[0])
    np.testing.assert_array_equal(w.velocities(), first[1])
    assert w.time == first[2]
    other = weft.World()
    other.add_cloth(weft.ClothDesc(rows=3, cols=3))
    with pytest.raises(weft.WeftError, match=r"snapshot particles.*length 256, expected 9"):
        other.restore(snap)


def test_reset_goes_back_to_the_start():
    w = hanging_world()
    x0 = w.positions()
    for _ in range(5):
        w.step()
    w.reset()
    np.testing.assert_array_equal(w.positions(), x0)
    assert w.steps == 0


def test_advance_takes_fixed_steps():
    w = hanging_world()
    r = w.advance(0.035)  # two 1/60 s steps and 0.1 of a step left
    assert (r.steps, r.capped) == (2, False)
    assert abs(r.alpha - 0.1) < 1e-4
    assert w.steps == 2
    r = w.advance(1.0)  # 60 steps owed, 8 taken
    assert r.steps == 8 and r.capped and r.dropped_time > 0.8
    between = w.interpolated_positions(0.5)
    assert between.shape == (256, 3)
    # Uneven frames give the same physics as even ones.
    a, b = hanging_world(), hanging_world()
    for _ in range(12):
        a.advance(1 / 60)
    for f in [0.005, 0.03, 0.001, 0.06, 0.1, 0.004]:
        b.advance(f)
    assert a.steps == b.steps == 12
    np.testing.assert_array_equal(a.positions(), b.positions())


def test_moving_a_pin():
    w = hanging_world()
    target = w.positions()[0] + np.array([0.0, 0.1, 0.0], dtype=np.float32)
    w.set_pin_position(0, target)
    w.step()
    np.testing.assert_array_equal(w.positions()[0], target)
    with pytest.raises(weft.WeftError, match="pinned"):
        w.set_pin_position(5, (0, 0, 0))


def test_wind_and_metrics():
    calm, windy = hanging_world(), hanging_world()
    windy.set_wind(weft.Wind((0.0, 0.0, 8.0)))
    for _ in range(30):
        calm.step()
        windy.step()
    dz = windy.positions()[:, 2].mean() - calm.positions()[:, 2].mean()
    assert dz > 0.01
    m = calm.metrics()
    assert set(m) == {"kinetic", "potential", "elastic", "total", "max_strain", "mean_strain"}
    assert m["kinetic"] > 0.0


def test_self_collision_failed_steps_count_the_refused_lists():
    # Two cloths and a distance that pairs every particle of one with every particle of the
    # other: more than 128 pairs a particle, so the step runs without self-collision.
    def sheet(y):
        return f"[[cloth]]\nrows = 30\ncols = 30\nspacing = 0.01\norigin = [0.0, {y}, 0.0]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 0.0, 1.0]\n"

    for distance, failed in ((0.01, 0), (1.0, 1)):
        w = weft.World.from_scene_text(f"[effects.self_collision]\ndistance = {distance}\n" + sheet(1.0) + sheet(1.02))
        w.step()
        assert w.self_collision_failed_steps == failed, distance
