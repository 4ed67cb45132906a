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
        counts, points = usd_core_reading(mine["source"])
        name = Path(mine["source"]).name
        problem = None
        if counts != mine["counts"]:
            problem = f"counts: usd-core {counts}, groombake {mine['counts']}"
        elif len(points) != len(mine["points"]):
            problem = f"points: usd-core {len(points)}, groombake {len(mine['points'])}"
        else:
            for index, (a, b) in enumerate(zip(points, mine["points"])):
                if not all(math.isclose(x, y, rel_tol=1e-5, abs_tol=1e-5) for x, y in zip(a, b)):
                    problem = f"point {index}: usd-core {a}, groombake {b}"
                    break
        if problem:
            failures += 1
            print(f"FAIL {name}: {problem}")
        else:
            print(f"ok   {name}: {len(counts)} curves, {len(points)} points as usd-core reads them")
    print(f"check_usd_fixtures: {len(readings)} fixtures, {failures} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
