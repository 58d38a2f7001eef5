"""Shapes, dtypes and the out= buffers of the read-back calls."""

import tracemalloc

import numpy as np
import pytest

import weft


def hanging(rows=6, cols=5, **kw):
    w = weft.World(**kw)
    w.add_cloth(weft.ClothDesc(rows=rows, cols=cols, spacing=0.1))
    return w


def test_read_back_shapes_and_dtypes():
    w = hanging()
    n = 30
    assert w.particle_count == n and len(w) == n
    w.step()
    for a in (w.positions(), w.velocities(), w.normals(), w.interpolated_positions(0.5)):
        assert a.shape == (n, 3)
        assert a.dtype == np.float32
        assert a.flags.c_contiguous
    for a in (w.positions_soa(), w.velocities_soa()):
        assert a.shape == (3, n) and a.dtype == np.float32
    t = w.triangles()
    assert t.shape == (2 * 5 * 4, 3) and t.dtype == np.uint32
    assert t.max() < n


def test_layouts_agree():
    w = hanging()
    for _ in range(5):
        w.step()
    x, v = w.positions(), w.velocities()
    np.testing.assert_array_equal(w.positions_soa(), x.T)
    np.testing.assert_array_equal(w.velocities_soa(), v.T)
    # The cloth moved, so the arrays are not trivially zero.
    assert np.abs(v).max() > 0.0


def test_initial_positions_follow_the_grid():
    w = weft.World()
    w.add_cloth(weft.ClothDesc(rows=3, cols=4, spacing=0.5, origin=(1.0, 2.0, 3.0), u=(1, 0, 0), v=(0, 0, 1)))
    x = w.positions()
    r, c = np.divmod(np.arange(12), 4)
    expected = np.stack([1.0 + 0.5 * c, np.full(12, 2.0), 3.0 + 0.5 * r], axis=1).astype(np.float32)
    np.testing.assert_allclose(x, expected, rtol=0, atol=1e-6)
    # A flat sheet in the x-z plane has normals along +-y.
    nrm = w.normals()
    np.testing.assert_allclose(np.abs(nrm[:, 1]), 1.0, atol=1e-6)


def test_out_buffer_is_filled_and_returned():
    w = hanging()
    w.step()
    buf = np.full((30, 3), np.nan, dtype=np.float32)
    got = w.positions(out=buf)
    assert got is buf
    np.testing.assert_array_equal(buf, w.positions())
    soa = np.zeros((3, 30), dtype=np.float32)
    assert w.velocities_soa(out=soa) is soa
    np.testing.assert_array_equal(soa, w.velocities().T)


@pytest.mark.parametrize(
    "bad",
    [
        np.zeros((29, 3), dtype=np.float32),
        np.zeros((30, 4), dtype=np.float32),
        np.zeros((30, 3), dtype=np.float64),
        np.zeros(90, dtype=np.float32),
        np.zeros((3, 30), dtype=np.float32).T,  # right shape, not C-contiguous
        [[0.0, 0.0, 0.0]] * 30,
    ],
)
def test_bad_out_buffer_raises(bad):
    w = hanging()
    with pytest.raises(weft.WeftError, match=r"positions out.*C-contiguous float32 array of shape \(30, 3\)"):
        w.positions(out=bad)


def test_read_only_out_buffer_raises():
    w = hanging()
    buf = np.zeros((30, 3), dtype=np.float32)
    buf.flags.writeable = False
    with pytest.raises(weft.WeftError, match="positions out"):
        w.positions(out=buf)


def test_refilling_a_buffer_allocates_no_array():
    """NumPy reports its array allocations to tracemalloc; refilling `out` must not add any."""
    w = hanging(rows=40, cols=40)  # a new (1600, 3) float32 array would be 19200 bytes
    w.step()
    buf = np.empty((1600, 3), dtype=np.float32)
    w.positions(out=buf)
    tracemalloc.start()
    try:
        base, _ = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        for _ in range(50):
            w.step()
            w.positions(out=buf)
            w.velocities(out=buf)
        _, peak = tracemalloc.get_traced_memory()
        assert peak - base < 19200, f"peak grew by {peak - base} bytes"
        # The check can fail: a fresh array is seen.
        tracemalloc.reset_peak()
        base, _ = tracemalloc.get_traced_memory()
        w.positions()
        _, peak = tracemalloc.get_traced_memory()
        assert peak - base >= 19200
    finally:
        tracemalloc.stop()
