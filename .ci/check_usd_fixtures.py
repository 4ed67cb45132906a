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
