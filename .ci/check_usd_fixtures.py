#!/usr/bin/env python3
"""Compares groombake's reading of the hand-written USD fixtures
(tests/data/usd/) with usd-core's.

usage: check_usd_fixtures.py DIR

DIR/usd_fixtures/<name>.groombake.json (written by tests/integration/usd.rs)
holds `source` (the fixture), `counts` and `points` as groombake read them.
usd-core opens the source (composition followed, instance proxies
traversed), and every BasisCurves prim's curveVertexCounts and points, in
world space (ComputeLocalToWorldTransform), at the default time (or the
first time sample), in traversal order, must equal groombake's to 1e-5.
A reading with `samples` (a file whose curveVertexCounts are time samples:
`[{"time_code", "counts", "points"}]`, as groombake's read_sequence gives
them) is compared at each of those time codes, and usd-core's time samples
of counts and points must be exactly those time codes.
A reading with `round_trip` (`{"source", "outputs"}`: groombake's
`convert --strict` of an OpenUSD test file to .usda and .usdc) compares
usd-core's reading of each output with its reading of the source: the same
BasisCurves prim paths in the same order, the same curve and vertex counts
per prim, world points to 1e-5, and each authored source width at each of
its places equal to the output's width there; time-sampled counts (a
changing topology) are compared at each of the source's time codes.
A reading with `prims` (OpenUSD's own test files, tests/data/usd/openusd/)
is compared prim by prim: the BasisCurves prims usd-core reads (counts
authored and not empty, as many points as the counts add up to) must be
groombake's prims, in order, with the same strand counts, counts and world
points, and every authored width must be groombake's, value by value, at
the points its interpolation gives it (constant: every point of the prim;
uniform: every point of its curve; vertex, and varying on linear curves:
its point; varying on cubic curves: the point of its segment end, point
j * vstep for bezier and periodic curves, j + 1 for nonperiodic and pinned
bspline and catmullRom; docs/formats.md).
Exits 1 on a difference, and when DIR holds no reading.
"""
import json
import math
import sys
from pathlib import Path

from pxr import Usd, UsdGeom


def usd_core_reading(source):
    stage = Usd.Stage.Open(str(source))
    counts, points = [], []
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        if not prim.IsA(UsdGeom.BasisCurves):
            continue
        curves = UsdGeom.BasisCurves(prim)
        time = Usd.TimeCode.Default()
        points_attr = curves.GetPointsAttr()
        if points_attr.Get(time) is None:
            samples = points_attr.GetTimeSamples()
            time = Usd.TimeCode(samples[0]) if samples else time
        counts.extend(curves.GetCurveVertexCountsAttr().Get(time) or [])
        world = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(time)
        points.extend(tuple(world.Transform(p)) for p in points_attr.Get(time) or [])
    return counts, points


def usd_core_reading_at(source, code):
    """Counts and world points of every BasisCurves prim at a time code."""
    stage = Usd.Stage.Open(str(source))
    counts, points, codes = [], [], set()
    time = Usd.TimeCode(code)
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        if not prim.IsA(UsdGeom.BasisCurves):
            continue
        curves = UsdGeom.BasisCurves(prim)
        codes.update(curves.GetCurveVertexCountsAttr().GetTimeSamples())
        codes.update(curves.GetPointsAttr().GetTimeSamples())
        counts.extend(curves.GetCurveVertexCountsAttr().Get(time) or [])
        world = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(time)
        points.extend(tuple(world.Transform(p)) for p in curves.GetPointsAttr().Get(time) or [])
    return counts, points, sorted(codes)


def reading_of_prims_at(source, paths, code):
    """Counts and world points of the prims at `paths` at a time code."""
    stage = Usd.Stage.Open(str(source))
    time = Usd.TimeCode(code)
    counts, points = [], []
    for path in paths:
        prim = stage.GetPrimAtPath(path)
        curves = UsdGeom.BasisCurves(prim)
        counts.extend(curves.GetCurveVertexCountsAttr().Get(time) or [])
        world = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(time)
        points.extend(tuple(world.Transform(p)) for p in curves.GetPointsAttr().Get(time) or [])
    return counts, points


def readable_prims(source):
    """usd-core's reading of every BasisCurves prim it can read: (path,
    counts, world points, widths or None, interpolation, type, basis,
    wrap)."""
    stage = Usd.Stage.Open(str(source))
    prims = []
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        if not prim.IsA(UsdGeom.BasisCurves):
            continue
        curves = UsdGeom.BasisCurves(prim)
        time = Usd.TimeCode.Default()
        samples = curves.GetCurveVertexCountsAttr().GetTimeSamples()
        if curves.GetCurveVertexCountsAttr().Get(time) is None and samples:
            # Time-sampled only (a changing topology): its first sample.
            time = Usd.TimeCode(samples[0])
        counts = curves.GetCurveVertexCountsAttr().Get(time)
        points = curves.GetPointsAttr().Get(time)
        if not counts or points is None or len(points) != sum(counts):
            continue
        world = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(time)
        widths = curves.GetWidthsAttr().Get(time)
        prims.append({
            "path": str(prim.GetPath()),
            "counts": list(counts),
            "points": [tuple(world.Transform(p)) for p in points],
            "widths": list(widths) if widths is not None and len(widths) else None,
            "interpolation": str(curves.GetWidthsInterpolation()),
            "type": str(curves.GetTypeAttr().Get()),
            "basis": str(curves.GetBasisAttr().Get()),
            "wrap": str(curves.GetWrapAttr().Get()),
        })
    return prims


def width_points(prim):
    """For each authored width, the points (indices in the prim) that must
    hold it."""
    counts, values = prim["counts"], prim["widths"]
    interpolation = prim["interpolation"]
    if len(values) == 1:
        interpolation = "constant"
    starts = [sum(counts[:i]) for i in range(len(counts))]
    if interpolation == "constant":
        return [list(range(sum(counts)))]
    if interpolation == "uniform":
        return [list(range(s, s + n)) for s, n in zip(starts, counts)]
    if interpolation == "vertex" or prim["type"] == "linear":
        return [[i] for i in range(sum(counts))]
    # Cubic varying: one per segment end.
    vstep = 3 if prim["basis"] == "bezier" else 1
    periodic = prim["wrap"] == "periodic"
    out = []
    for s, n in zip(starts, counts):
        ends = n // vstep if periodic else max((n - 4) // vstep, 0) + 2
        for j in range(ends):
            k = j * vstep if (vstep == 3 or periodic) else j + 1
            out.append([s + min(k, n - 1)])
    return out


def prim_difference(source, mine):
    theirs = readable_prims(source)
    paths = [p["path"] for p in theirs]
    mine_paths = [p for p, _ in mine["prims"]]
    if paths != mine_paths:
        return f"prims: usd-core {paths}, groombake {mine_paths}"
    strands = [len(p["counts"]) for p in theirs]
    mine_strands = [n for _, n in mine["prims"]]
    if strands != mine_strands:
        return f"strands per prim: usd-core {strands}, groombake {mine_strands}"
    counts = [c for p in theirs for c in p["counts"]]
    points = [x for p in theirs for x in p["points"]]
    problem = difference(counts, points, mine["counts"], mine["points"])
    if problem:
        return problem
    start = 0
    compared = 0
    for prim in theirs:
        if prim["widths"] is not None:
            if mine["widths"] is None:
                return f"{prim['path']}: usd-core reads widths, groombake none"
            groups = width_points(prim)
            if len(groups) != len(prim["widths"]):
                return f"{prim['path']}: {len(prim['widths'])} widths, {len(groups)} places"
            for value, group in zip(prim["widths"], groups):
                for index in group:
                    got = mine["widths"][start + index]
                    if not math.isclose(value, got, rel_tol=1e-6, abs_tol=1e-7):
                        return f"{prim['path']}: width at point {index}: usd-core {value}, groombake {got}"
                    compared += 1
        start += sum(prim["counts"])
    return compared


def per_point_widths(prim):
    """The width at each point of a prim, None where the source authors
    none (cubic varying widths leave the points between segment ends)."""
    out = [None] * sum(prim["counts"])
    if prim["widths"] is None:
        return out
    groups = width_points(prim)
    if len(groups) != len(prim["widths"]):
        return None
    for value, group in zip(prim["widths"], groups):
        for index in group:
            out[index] = value
    return out


def round_trip_difference(source, output):
    """What differs between usd-core's readings of a source and of
    groombake's output of it, or a count of compared values."""
    theirs, mine = readable_prims(source), readable_prims(output)
    paths, mine_paths = [p["path"] for p in theirs], [p["path"] for p in mine]
    if paths != mine_paths:
        return f"prim paths: source {paths}, output {mine_paths}"
    compared = 0
    for a, b in zip(theirs, mine):
        if a["counts"] != b["counts"]:
            return f"{a['path']}: counts: source {a['counts']}, output {b['counts']}"
        if (a["type"], a["basis"], a["wrap"]) != (b["type"], b["basis"], b["wrap"]):
            return f"{a['path']}: curves: source {(a['type'], a['basis'], a['wrap'])}, output {(b['type'], b['basis'], b['wrap'])}"
        problem = difference(a["counts"], a["points"], b["counts"], b["points"])
        if problem:
            return f"{a['path']}: {problem}"
        want, got = per_point_widths(a), per_point_widths(b)
        if want is None or got is None:
            return f"{a['path']}: widths do not fit their interpolation"
        for index, (w, g) in enumerate(zip(want, got)):
            if w is None:
                continue
            if g is None or not math.isclose(w, g, rel_tol=1e-6, abs_tol=1e-7):
                return f"{a['path']}: width at point {index}: source {w}, output {g}"
            compared += 1
        if a["widths"] is None and b["widths"] is not None:
            return f"{a['path']}: the source has no widths, the output {len(b['widths'])}"
        compared += len(a["points"])
    # A changing topology: every time code of the readable prims' counts.
    stage = Usd.Stage.Open(str(source))
    codes = sorted({
        code
        for path in paths
        for code in UsdGeom.BasisCurves(stage.GetPrimAtPath(path))
        .GetCurveVertexCountsAttr().GetTimeSamples()
    })
    for code in codes:
        want = reading_of_prims_at(source, paths, code)
        got = reading_of_prims_at(output, paths, code)
        problem = difference(want[0], want[1], got[0], got[1])
        if problem:
            return f"at time code {code}: {problem}"
        compared += len(want[1])
    return compared


def difference(counts, points, mine_counts, mine_points):
    """What differs between usd-core's reading and groombake's, or None."""
    if counts != mine_counts:
        return f"counts: usd-core {counts}, groombake {mine_counts}"
    if len(points) != len(mine_points):
        return f"points: usd-core {len(points)}, groombake {len(mine_points)}"
    for index, (a, b) in enumerate(zip(points, mine_points)):
        if not all(math.isclose(x, y, rel_tol=1e-5, abs_tol=1e-5) for x, y in zip(a, b)):
            return f"point {index}: usd-core {a}, groombake {b}"
    return None


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    readings = sorted(Path(sys.argv[1]).glob("usd_fixtures/*.groombake.json"))
    if not readings:
        print("check_usd_fixtures: no groombake reading to compare", file=sys.stderr)
        return 1
    failures = 0
    for path in readings:
        mine = json.loads(path.read_text())
        name = Path(mine["source"]).name
        if "samples" in mine:
            problem = None
            codes = []
            for sample in mine["samples"]:
                counts, points, codes = usd_core_reading_at(mine["source"], sample["time_code"])
                problem = difference(counts, points, sample["counts"], sample["points"])
                if problem:
                    problem = f"at time code {sample['time_code']}: {problem}"
                    break
            mine_codes = [s["time_code"] for s in mine["samples"]]
            if not problem and codes != mine_codes:
                problem = f"time codes: usd-core {codes}, groombake {mine_codes}"
            if problem:
                failures += 1
                print(f"FAIL {name}: {problem}")
            else:
                print(f"ok   {name}: counts and points at time codes {mine_codes} "
                      "as usd-core reads them")
            continue
        if "round_trip" in mine:
            trip = mine["round_trip"]
            for output in trip["outputs"]:
                problem = round_trip_difference(trip["source"], output)
                if isinstance(problem, str):
                    failures += 1
                    print(f"FAIL {name} -> {Path(output).name}: {problem}")
                else:
                    print(f"ok   {name} -> {Path(output).name}: prim paths, counts, "
                          f"{problem} points and widths as in the source")
            continue
        if "prims" in mine:
            problem = prim_difference(mine["source"], mine)
            if isinstance(problem, str):
                failures += 1
                print(f"FAIL {name}: {problem}")
            else:
                print(f"ok   {name}: {len(mine['prims'])} prims, {len(mine['counts'])} curves, "
                      f"{len(mine['points'])} points and {problem} width places as usd-core reads them")
            continue
        counts, points = usd_core_reading(mine["source"])
        problem = difference(counts, points, mine["counts"], mine["points"])
        if problem:
            failures += 1
            print(f"FAIL {name}: {problem}")
        else:
            print(f"ok   {name}: {len(counts)} curves, {len(points)} points as usd-core reads them")
    print(f"check_usd_fixtures: {len(readings)} fixtures, {failures} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
