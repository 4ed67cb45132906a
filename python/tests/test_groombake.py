"""The groombake Python module, tested through its public API.

GROOMBAKE_BIN names the CLI binary whose bytes `bake` must reproduce
(default: target/debug/groombake beside the workspace, or under
CARGO_TARGET_DIR).
"""

import os
import pathlib
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import groombake as gb

ROOT = pathlib.Path(__file__).resolve().parents[2]
FORMATS = ["abc", "usda", "usdc", "glb", "gltf", "hair", "data", "obj"]


def cli_binary():
    if os.environ.get("GROOMBAKE_BIN"):
        return os.environ["GROOMBAKE_BIN"]
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return str(target / "debug" / "groombake")


def sample_groom():
    rng = np.random.default_rng(7)
    counts = np.array([5, 4, 6, 3], dtype=np.int32)
    points = (rng.random((counts.sum(), 3)) * 20.0).astype(np.float32)
    return points, counts


TIMELINE = """
seed = 3
[groom]
generate = {{ layout = "swatch", strands = 6, length = 0.1, segment_length = 0.02, swatch_width = 0.04, head_center = [0.0, 0.2, 0.0] }}
[solver]
dt = "1/360"
iterations = 4
[[stage]]
kind = "wet"
duration = {wet}
[[stage]]
kind = "dry"
duration = {dry}
[[export]]
path = "out/anim.abc"
what = "animated"
fps = 24
[[export]]
path = "out/rest.usda"
what = "rest"
[[export]]
path = "out/state.glb"
what = "state"
"""


def write_timeline(folder, wet=0.2, dry=0.8):
    path = folder / "t.toml"
    path.write_text(TIMELINE.format(wet=wet, dry=dry))
    return path


@pytest.mark.parametrize("ext", FORMATS)
def test_round_trip_through_numpy(tmp_path, ext):
    points, counts = sample_groom()
    first = tmp_path / f"a.{ext}"
    gb.Groom.from_arrays(points, counts, units="cm").save(str(first))
    loaded = gb.load(str(first), units="cm", up="y")
    assert loaded.points.dtype == np.float32 and loaded.points.shape == (len(points), 3)
    assert loaded.counts.dtype == np.int32
    np.testing.assert_array_equal(loaded.counts, counts)
    np.testing.assert_allclose(loaded.points, points, rtol=1e-6, atol=1e-5)
    # Arrays out, a groom from them, written and read again: the same.
    again = tmp_path / f"b.{ext}"
    gb.Groom.from_arrays(loaded.points, loaded.counts, units=loaded.units, up=loaded.up).save(str(again))
    reread = gb.load(str(again), units="cm", up="y")
    np.testing.assert_array_equal(reread.counts, loaded.counts)
    np.testing.assert_allclose(reread.points, loaded.points, rtol=1e-6, atol=1e-5)


def test_from_arrays_save_load_keeps_attributes_and_frames(tmp_path):
    points, counts = sample_groom()
    frames = np.stack([points + k for k in range(3)])
    groom = gb.Groom.from_arrays(
        points,
        counts,
        frames=frames,
        times=[0.0, 0.5, 1.0],
        units="cm",
        temperature=np.linspace(0, 1, len(points)),
        ids=np.arange(len(counts), dtype=np.int32),
        tint=(np.ones((len(counts), 3)), "strand"),
    )
    path = tmp_path / "g.usda"
    groom.save(str(path))
    back = gb.load(str(path), units="cm")
    np.testing.assert_array_equal(back.counts, counts)
    np.testing.assert_allclose(back.points, points, atol=1e-5)
    assert len(back.frames) == 3
    for (t, p), expected_t, expected in zip(back.frames, [0.0, 0.5, 1.0], frames):
        assert abs(t - expected_t) < 1e-9
        np.testing.assert_allclose(p, expected, atol=1e-5)
    attributes = back.attributes
    values, scope = attributes["temperature"]
    assert scope == "vertex" and values.dtype == np.float32
    np.testing.assert_allclose(values, np.linspace(0, 1, len(points)), atol=1e-7)
    values, scope = attributes["ids"]
    assert scope == "strand" and values.dtype == np.int32
    np.testing.assert_array_equal(values, np.arange(len(counts)))
    assert attributes["tint"][1] == "strand" and attributes["tint"][0].shape == (len(counts), 3)


def test_from_arrays_refuses_bad_arrays():
    points, counts = sample_groom()
    with pytest.raises(gb.BadInput, match="counts sum to"):
        gb.Groom.from_arrays(points, counts[:-1])
    with pytest.raises(gb.BadInput, match="attribute w: 5 values"):
        gb.Groom.from_arrays(points, counts, w=np.zeros(5))
    with pytest.raises(gb.BadInput):
        gb.load("/nonexistent/groom.abc")


def test_bake_gives_the_cli_bytes(tmp_path):
    timeline = write_timeline(tmp_path)
    subprocess.run([cli_binary(), "bake", str(timeline), "--out", str(tmp_path / "cli"), "-q"], check=True)
    report = gb.bake(gb.Timeline.load(str(timeline)), out=str(tmp_path / "py"), threads=1)
    assert len(report.outputs) == 3
    for output in report.outputs:
        relative = pathlib.Path(output["path"]).relative_to(tmp_path / "py")
        py_bytes = (tmp_path / "py" / relative).read_bytes()
        assert py_bytes == (tmp_path / "cli" / relative).read_bytes(), relative
        assert output["bytes"] == len(py_bytes)
    assert [s["kind"] for s in report.stages] == ["wet", "dry"]
    assert report.to_dict()["strands"] == 6


def test_bad_dict_names_the_key_path():
    good = {
        "groom": {"generate": {"layout": "swatch", "strands": 3, "length": 0.1}},
        "stage": [{"kind": "wet", "duration": 0.3}, {"kind": "dry", "duration": 1.0}],
    }
    assert gb.Timeline.from_dict(good).duration == pytest.approx(1.3)
    bad = {**good, "stage": [good["stage"][0], {"kind": "dry", "duration": -1.0}]}
    with pytest.raises(gb.BadInput, match=r"stage\[1\]\.duration"):
        gb.Timeline.from_dict(bad)
    typo = {**good, "solver": {"damping": {"linear": 0.1, "angullar": 0.2}}}
    with pytest.raises(gb.BadInput, match=r"solver\.damping\.angullar"):
        gb.Timeline.from_dict(typo)
    with pytest.raises(gb.BadInput, match=r"groom\.generate\.strands"):
        gb.Timeline.from_dict({**good, "groom": {"generate": {"layout": "swatch", "strands": None}}})


def test_the_report_is_finished_as_the_cli_writes_it(tmp_path):
    timeline = write_timeline(tmp_path)
    subprocess.run(
        [cli_binary(), "bake", str(timeline), "--out", str(tmp_path / "cli"), "-q", "--report", str(tmp_path / "r.json")],
        check=True,
    )
    cli = __import__("json").loads((tmp_path / "r.json").read_text())
    report = gb.bake(str(timeline), out=str(tmp_path / "py"), threads=1)
    assert report.status == "ok" and report.exit_code == 0 and report.error is None
    assert report.started <= report.finished and report.finished.endswith("Z"), report.finished
    assert report.peak_memory_bytes > 0
    assert [o["sha256"] for o in report.outputs] == [o["sha256"] for o in cli["outputs"]]
    assert report.timeline_sha256 == cli["timeline_sha256"]
    assert report.warnings == cli["warnings"]
    assert set(report.to_dict()) == set(cli), "the same keys as the CLI's report"
    names = dir(report)
    for key in ["status", "finished", "outputs", "stages", "sources", "warnings", "to_dict"]:
        assert key in names, key


def test_progress_gets_the_stage_and_the_fraction(tmp_path):
    seen = []
    gb.bake(str(write_timeline(tmp_path, dry=1.5)), out=str(tmp_path), progress=lambda f, stage: seen.append((f, stage)))
    stages = [stage for _, stage in seen]
    assert stages[0] == "wet" and stages[-1] == "dry", seen
    assert stages == sorted(stages, key=["wet", "dry"].index), "stages in order"
    fractions = [f for f, _ in seen]
    assert all(b >= a for a, b in zip(fractions, fractions[1:])) and fractions[-1] == 1.0


def test_progress_is_monotone_and_reaches_one(tmp_path):
    values = []
    gb.bake(str(write_timeline(tmp_path, dry=1.5)), out=str(tmp_path), progress=values.append)
    assert len(values) >= 2, values
    assert all(b >= a for a, b in zip(values, values[1:])), values
    assert 0.0 <= values[0] and values[-1] == 1.0


def test_bake_releases_the_gil(tmp_path):
    timeline = gb.Timeline.load(str(write_timeline(tmp_path, dry=100.0)))
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            for _ in range(2000):  # pure Python work: needs the GIL
                pass

    thread = threading.Thread(target=count)
    thread.start()
    started = time.perf_counter()
    gb.bake(timeline, out=str(tmp_path), threads=1)
    ended = time.perf_counter()
    stop.set()
    thread.join()
    during = [t for t in ticks if started <= t <= ended]
    gaps = np.diff([started] + during + [ended])
    print(f"bake {ended - started:.2f} s: other thread ran {len(during)} loops, longest stall {gaps.max() * 1000:.0f} ms")
    assert ended - started > 0.3, "the bake is too short to measure"
    assert len(during) > 50
    assert gaps.max() < 0.5


def test_ctrl_c_interrupts_cleanly(tmp_path):
    timeline = write_timeline(tmp_path, dry=200.0)
    script = f"""
import groombake, sys
seen = []
def progress(f):
    if not seen:
        print("started", flush=True)
    seen.append(f)
try:
    groombake.bake({str(timeline)!r}, out={str(tmp_path / 'out')!r}, threads=1, progress=progress)
except KeyboardInterrupt:
    print("interrupted", flush=True)
    sys.exit(3)
"""
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "started"
    time.sleep(0.3)
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=60)
    assert child.returncode == 3 and "interrupted" in out
    left = [p for p in (tmp_path / "out").rglob("*") if p.is_file()]
    assert left == [], left
