"""The Python module's limits (issue 37): deep, cyclic and out-of-range
input raises BadInput, never a crash of the interpreter or a silent wrap."""

import subprocess
import sys

import numpy as np
import pytest

import groombake as gb

GOOD = {
    "groom": {"generate": {"layout": "swatch", "strands": 3, "length": 0.1}},
    "stage": [{"kind": "wet", "duration": 0.3}],
}


def run_isolated(code):
    """Runs `code` in a fresh interpreter: a segfault there fails the test
    instead of killing pytest."""
    done = subprocess.run([sys.executable, "-c", "import groombake as gb\n" + code],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    return done.stdout


@pytest.mark.parametrize("build", [
    # 7,000 nested lists and 20,000 nested dicts once overflowed the stack.
    "x = 0\nfor _ in range(7000): x = [x]\nd = {**GOOD, 'seed': x}",
    "x = 0\nfor _ in range(20000): x = {'a': x}\nd = {**GOOD, 'solver': x}",
    "x = []\nx.append(x)\nd = {**GOOD, 'seed': x}",
    "x = {}\nx['a'] = x\nd = {**GOOD, 'solver': x}",
    "d = dict(GOOD)\nd['groom'] = d",
])
def test_deep_and_cyclic_dicts_raise_bad_input(build):
    out = run_isolated(f"""
GOOD = {GOOD!r}
{build}
try:
    gb.Timeline.from_dict(d)
except gb.BadInput as e:
    print("BadInput:", e)
""")
    assert "BadInput:" in out and ("nested more than" in out or "contains itself" in out), out


def test_numpy_arrays_in_a_dict_go_through_tolist():
    d = {**GOOD, "stage": [{"kind": "wet", "duration": np.float64(0.3)}],
         "groom": {"generate": {"layout": "swatch", "strands": np.int64(3), "length": np.float32(0.1)}},
         "collider": [{"name": "floor", "shape": {"half_space": {"normal": np.array([0.0, 1.0, 0.0])}}}]}
    assert gb.Timeline.from_dict(d).duration == pytest.approx(0.3)


def test_threads_are_capped_as_the_cli_caps_them(tmp_path):
    timeline = gb.Timeline.from_dict(GOOD)
    for threads in [0, 1025, 10**6, -1, 10**30]:
        with pytest.raises(gb.BadInput, match="threads must be 1 to 1024"):
            gb.bake(timeline, out=str(tmp_path), threads=threads)


def sample():
    points = np.arange(18, dtype=np.float32).reshape(6, 3)
    return points, np.array([3, 3])


def test_int_attributes_are_range_checked_not_wrapped():
    points, counts = sample()
    for values in [np.array([2**40, 1]), np.array([-2**31 - 1, 0]), np.array([2**63, 1], dtype=np.uint64)]:
        with pytest.raises(gb.BadInput, match=r"attribute ids\[0\]: .* int32 range"):
            gb.Groom.from_arrays(points, counts, ids=values)
    groom = gb.Groom.from_arrays(points, counts, ids=np.array([2**31 - 1, -2**31]))
    np.testing.assert_array_equal(groom.attributes["ids"][0], [2**31 - 1, -2**31])


def test_from_arrays_refuses_what_save_would_refuse(tmp_path):
    points, counts = sample()
    frames = np.stack([points, points])
    for times in [[0.0, float("inf")], [0.0, float("nan")], [-1.0, 0.0], [0.5, 0.5], [0.0, 4.2e-45]]:
        with pytest.raises(gb.BadInput, match=r"times\[[01]\]"):
            gb.Groom.from_arrays(points, counts, frames=frames, times=times)
    huge = points.copy()
    huge[2, 1] = 3e38
    with pytest.raises(gb.BadInput, match=r"points\[2\]"):
        gb.Groom.from_arrays(huge, counts)
    with pytest.raises(gb.BadInput, match=r"frames\[1\]\[2\]"):
        gb.Groom.from_arrays(points, counts, frames=np.stack([points, huge]), times=[0.0, 1.0])
    # What it accepts, every format writes.
    groom = gb.Groom.from_arrays(points, counts, frames=frames, times=[0.0, 1e-6])
    for ext in ["abc", "usda", "usdc", "glb"]:
        groom.save(str(tmp_path / f"g.{ext}"))
