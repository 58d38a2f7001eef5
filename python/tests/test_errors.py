"""Every bad input raises weft.WeftError with the library's message."""

import math

import numpy as np
import pytest

import weft


def test_weft_error_is_a_value_error():
    assert issubclass(weft.WeftError, ValueError)
    assert issubclass(weft.DivergedError, weft.WeftError)


@pytest.mark.parametrize(
    "kw, message",
    [
        ({"dt": -1.0}, r"invalid parameter `solver.dt` = -1: must be a finite number greater than zero"),
        ({"dt": math.nan}, r"`solver.dt` = NaN"),
        ({"substeps": 0}, r"`solver.substeps` = 0: must be between 1 and"),
        ({"threads": 5000}, r"`solver.threads` = 5000"),
        ({"method": "rk4"}, r"`solver.method` = rk4: expected one of xpbd"),
        ({"backend": "gpu"}, r"`solver.backend` = gpu"),
        ({"gravity": (0.0, math.inf, 0.0)}, r"`effects.gravity`.*finite"),
        ({"drag": -0.5}, r"`effects.drag` = -0.5"),
        ({"friction": math.nan}, r"`friction` = NaN"),
    ],
)
def test_bad_world_parameters(kw, message):
    with pytest.raises(weft.WeftError, match=message):
        weft.World(**kw)


def test_bad_cloth():
    with pytest.raises(weft.WeftError, match=r"`fabric` = silk: unknown preset; expected one of basic, cotton, wool, polyester"):
        weft.ClothDesc(fabric="silk")
    with pytest.raises(weft.WeftError, match=r"`fabric.mass` = NaN"):
        weft.ClothDesc(mass=math.nan)
    with pytest.raises(weft.WeftError, match=r"`pins`.*first-row-corners"):
        weft.ClothDesc(pins=["corners"])
    with pytest.raises(weft.WeftError, match=r"`pins`.*`row` needs a row number"):
        weft.ClothDesc(pins=[{"row": "top"}])
    w = weft.World()
    with pytest.raises(weft.WeftError, match=r"spacing"):
        w.add_cloth(weft.ClothDesc(spacing=math.nan))
    with pytest.raises(weft.WeftError, match=r"rows"):
        w.add_cloth(weft.ClothDesc(rows=0))
    assert w.particle_count == 0


def test_bad_obstacles():
    w = weft.World()
    with pytest.raises(weft.WeftError, match=r"`sphere.radius` = NaN"):
        w.add_sphere((0, 0, 0), math.nan)
    with pytest.raises(weft.WeftError, match=r"`plane.normal`.*not zero"):
        w.add_plane((0, 0, 0), (0, 0, 0))
    with pytest.raises(weft.WeftError, match=r"`capsule.radius` = -1"):
        w.add_capsule((0, 0, 0), (1, 0, 0), -1.0)
    with pytest.raises(weft.WeftError, match=r"`box.half_extents` = 0"):
        w.add_box((0, 0, 0), (1, 0, 1))
    with pytest.raises(weft.WeftError, match=r"`obstacle.velocity`"):
        w.add_sphere((0, 0, 0), 1.0, velocity=(math.nan, 0, 0))
    with pytest.raises(weft.WeftError, match=r"invalid mesh: vertex 1 is not finite"):
        w.add_mesh(np.array([[0, 0, 0], [1, math.nan, 0], [0, 0, 1]]), np.array([[0, 1, 2]]))
    with pytest.raises(weft.WeftError, match=r"face 0 uses vertex 7 but there are only 3 vertices"):
        w.add_mesh(np.eye(3), np.array([[0, 1, 7]]))
    with pytest.raises(weft.WeftError, match=r"vertex indices must be between 0"):
        w.add_mesh(np.eye(3), np.array([[0, 1, -2]]))
    with pytest.raises(weft.WeftError, match=r"`mesh.vertices`.*shape \(m, 3\)"):
        w.add_mesh(np.zeros((3, 2)), np.array([[0, 1, 2]]))
    with pytest.raises(weft.WeftError, match=r"`mesh.broadphase` = octree"):
        w.add_mesh(np.eye(3), np.array([[0, 1, 2]]), broadphase="octree")
    assert w.obstacle_count == 0


def test_bad_effects():
    with pytest.raises(weft.WeftError, match=r"`effects.wind.air_density` = 0"):
        weft.Wind((1.0, 0.0, 0.0), air_density=0.0)
    with pytest.raises(weft.WeftError, match=r"`self_collision.response` = soft"):
        weft.SelfCollision(response="soft")
    with pytest.raises(weft.WeftError, match=r"friction"):
        weft.SelfCollision(friction=2.0)
    for travel in (0.0, 2.5, math.nan):
        with pytest.raises(weft.WeftError, match=r"`self_collision.travel`"):
            weft.SelfCollision(travel=travel)
    assert "travel=0.5" in repr(weft.SelfCollision(travel=0.5))


def test_bad_step_and_advance():
    w = weft.World()
    w.add_cloth(weft.ClothDesc(rows=4, cols=4))
    with pytest.raises(weft.WeftError, match=r"invalid parameter `dt` = NaN"):
        w.step(math.nan)
    with pytest.raises(weft.WeftError, match=r"`dt` = -0.1"):
        w.step(-0.1)
    with pytest.raises(weft.WeftError, match=r"`frame_dt` = inf"):
        w.advance(math.inf)
    with pytest.raises(weft.WeftError, match=r"`alpha` = 2"):
        w.interpolated_positions(2.0)
    with pytest.raises(weft.WeftError, match=r"`particle` index 99 is out of range \(there are 16\)"):
        w.set_pin_position(99, (0, 0, 0))
    assert w.steps == 0


def test_bad_scene_files(tmp_path):
    missing = tmp_path / "missing.toml"
    with pytest.raises(weft.WeftError, match=r"i/o error on `.*missing.toml`"):
        weft.World.from_scene(missing)
    bad = tmp_path / "bad.toml"
    bad.write_text("[solver]\ndt = 0.01\nsubstepz = 3\n")
    with pytest.raises(weft.WeftError, match=r"scene error: .*bad.toml at line 3, column 1: unknown field `substepz`"):
        weft.World.from_scene(str(bad))
    with pytest.raises(weft.WeftError, match=r"scene error"):
        weft.World.from_scene_text("[[cloth]]\nrows = 4\ncols = 4\nspacing = -1.0\n")
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(weft.WeftError, match=r"i/o error on `.*binary.toml`"):
        weft.World.from_scene(binary)


def test_divergence_raises_and_keeps_the_state():
    # A stiff spring model stepped far beyond its stable step blows up.
    w = weft.World(method="symplectic-euler", stiffness=1e9, substeps=1, gravity=(0.0, -9.81, 0.0))
    w.add_cloth(weft.ClothDesc(rows=8, cols=8, spacing=0.01, fabric="cotton"))
    before = None
    with pytest.raises(weft.DivergedError, match=r"step diverged: particle \d+ became non-finite"):
        for _ in range(200):
            before = w.positions()
            w.step(0.1)
    assert np.isfinite(w.positions()).all()
    np.testing.assert_array_equal(w.positions(), before)
