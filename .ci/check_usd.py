#!/usr/bin/env python3
"""Checks every USD file the tests exported with usd-core, the reference
implementation.

usage: check_usd.py DIR

For each `.usda`/`.usdc`/`.usd` in DIR: opens it with `Usd.Stage.Open`,
checks prim types, curve and point counts (at the default time and at every
time sample), widths and primvar sizes against their interpolation
(`ComputeInterpolationForSize`), the authored extent against the one usd-core
computes, the time-code range, and the expectations the test wrote beside
the file in `<file>.expect.json` (keys: curves, points, prims, first_point,
meters_per_unit, up_axis, basis, time_samples, start_time_code,
end_time_code, time_codes_per_second, widths and primvars (their
interpolation in every curves prim that has them, some prim must), and sample_points:
`[time code, point index, [x, y, z]]` items checked in the first curves prim,
and topology: `[time code, curves, points]` items for a file whose
curveVertexCounts are time samples; frame_values: `{primvar: [[time code,
"min_above" or "max_below", bound], ...]}`, the primvar's time-sampled
values at that time code in every curves prim; time_varying: the primvars
that must have time samples, every other primvar must have none, so the
attributes that hold still are written once). A file with time-sampled counts is
checked at its first time sample where others are checked at the default
time, and its counts must fit its points at every time sample.
Every file must also pass all of usd-core's registered validators
(`UsdValidation.ValidationRegistry().GetOrLoadAllValidators()`) with no
error. Exits 1 on any failure or when DIR holds no USD file.
"""
import json
import math
import sys
from pathlib import Path

from pxr import Gf, Sdf, Usd, UsdGeom, UsdValidation

EXTENSIONS = {".usda", ".usdc", ".usd"}
KNOWN_TYPES = {"Xform", "Scope", "BasisCurves"}


def close(a, b, tolerance=1e-5):
    a, b = list(a), list(b)
    return len(a) == len(b) and all(
        math.isclose(x, y, rel_tol=tolerance, abs_tol=tolerance) for x, y in zip(a, b))


def fits(curves, size, interpolation, time=Usd.TimeCode.Default()):
    """Whether `size` values fit `interpolation` on these curves at `time`.
    For linear curves vertex and varying have the same size, so the one
    usd-core's ComputeInterpolationForSize names first may be either."""
    if not curves.ComputeInterpolationForSize(size, time):
        return False
    expected = {
        "constant": 1,
        "uniform": curves.ComputeUniformDataSize(time),
        "varying": curves.ComputeVaryingDataSize(time),
        "vertex": curves.ComputeVertexDataSize(time),
    }.get(interpolation)
    return expected == size


_VALIDATION = None


def validation_context():
    """All of usd-core's built-in validators, loaded once."""
    global _VALIDATION
    if _VALIDATION is None:
        validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
        _VALIDATION = (UsdValidation.ValidationContext(validators), len(validators))
    return _VALIDATION


def validator_errors(path):
    """The errors usd-core's validators report on the file's stage."""
    context, _ = validation_context()
    stage = Usd.Stage.Open(str(path))
    return [
        f"validator {error.GetName()}: {error.GetMessage()}"
        for error in context.Validate(stage)
        if error.GetType() == UsdValidation.ValidationErrorType.Error
    ]


def check_file(path):
    """Returns the list of problems of one file."""
    problems = []
    fail = problems.append
    sidecar = Path(str(path) + ".expect.json")
    if not sidecar.exists():
        return [f"no expectations file {sidecar.name}"]
    expect = json.loads(sidecar.read_text())
    stage = Usd.Stage.Open(str(path))
    if stage is None:
        return ["usd-core cannot open it"]

    # An Xform root (groombake's `Groom`, or a source's parent kept), or a
    # source's root curves prim kept at its path.
    default = stage.GetDefaultPrim()
    if not default or default.GetTypeName() not in ("Xform", "BasisCurves"):
        fail("the default prim is not an Xform or a curves prim")
    # Expected widths and primvars: every curves prim that has one has it
    # at the expected interpolation, and some prim has it (a prim kept from
    # a source prim that lacked it lacks it too).
    seen_widths = False
    seen_primvars = set()
    curves_prims = []
    for prim in stage.Traverse():
        if prim.GetTypeName() not in KNOWN_TYPES:
            fail(f"{prim.GetPath()}: unexpected prim type '{prim.GetTypeName()}'")
        if prim.IsA(UsdGeom.BasisCurves):
            curves_prims.append(UsdGeom.BasisCurves(prim))
    if not curves_prims:
        return problems + ["no BasisCurves prim"]

    if "meters_per_unit" in expect and not close(
            [UsdGeom.GetStageMetersPerUnit(stage)], [expect["meters_per_unit"]], 1e-12):
        fail(f"metersPerUnit {UsdGeom.GetStageMetersPerUnit(stage)} != {expect['meters_per_unit']}")
    if "up_axis" in expect and UsdGeom.GetStageUpAxis(stage) != expect["up_axis"]:
        fail(f"upAxis {UsdGeom.GetStageUpAxis(stage)} != {expect['up_axis']}")

    start, end = stage.GetStartTimeCode(), stage.GetEndTimeCode()
    for key, actual in (("start_time_code", start), ("end_time_code", end),
                        ("time_codes_per_second", stage.GetTimeCodesPerSecond())):
        if key in expect and not close([actual], [expect[key]], 1e-12):
            fail(f"{key} {actual} != {expect[key]}")

    total_curves = total_points = 0
    first_point = None
    all_samples = None
    topology = []
    for curves in curves_prims:
        prim_path = curves.GetPath()
        counts_attribute = curves.GetCurveVertexCountsAttr()
        # Time-sampled counts (a topology that changes) have no default:
        # the first sample stands for it.
        count_times = counts_attribute.GetTimeSamples()
        rest = Usd.TimeCode(count_times[0]) if counts_attribute.Get() is None and count_times \
            else Usd.TimeCode.Default()
        counts = counts_attribute.Get(rest)
        points_attribute = curves.GetPointsAttr()
        points = points_attribute.Get(rest)
        if counts is None or points is None:
            fail(f"{prim_path}: no curveVertexCounts or points")
            continue
        total_curves += len(counts)
        total_points += len(points)
        if sum(counts) != len(points):
            fail(f"{prim_path}: counts add up to {sum(counts)}, {len(points)} points")
        world = UsdGeom.Xformable(curves).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
        if first_point is None and len(points):
            first_point = world.Transform(Gf.Vec3d(points[0]))

        times = points_attribute.GetTimeSamples()
        if times:
            if times[0] < start or times[-1] > end:
                fail(f"{prim_path}: samples {times[0]}..{times[-1]} outside {start}..{end}")
            samples = {}
            for t in times:
                sample = points_attribute.Get(t)
                counts_then = counts_attribute.Get(t) or []
                if len(sample) != sum(counts_then):
                    fail(f"{prim_path}: {len(sample)} points at time {t}, "
                         f"counts add up to {sum(counts_then)}")
                if count_times:
                    topology.append([t, len(counts_then), len(sample)])
                    for name, values in (("widths", curves.GetWidthsAttr().Get(t)),):
                        interpolation = curves.GetWidthsInterpolation()
                        if values is not None and not fits(curves, len(values), interpolation,
                                                           Usd.TimeCode(t)):
                            fail(f"{prim_path}: {len(values)} {name} do not fit at time {t}")
                samples[t] = [world.Transform(Gf.Vec3d(p)) for p in sample]
            all_samples = all_samples or samples

        checked_times = [rest] + [Usd.TimeCode(t) for t in times]
        for time in checked_times:
            authored = curves.GetExtentAttr().Get(time)
            computed = UsdGeom.Boundable.ComputeExtentFromPlugins(curves, time)
            if authored is None or computed is None:
                fail(f"{prim_path}: no extent at {time}")
            elif not all(close(a, c, 1e-4) for a, c in zip(authored, computed)):
                fail(f"{prim_path}: extent {list(authored)} != computed {list(computed)} at {time}")

        curve_type = curves.GetTypeAttr().Get()
        basis = "linear" if curve_type == "linear" else curves.GetBasisAttr().Get()
        if "basis" in expect and basis != expect["basis"]:
            fail(f"{prim_path}: basis {basis} != {expect['basis']}")

        widths = curves.GetWidthsAttr().Get(rest)
        if widths is not None:
            interpolation = curves.GetWidthsInterpolation()
            if not fits(curves, len(widths), interpolation, rest):
                fail(f"{prim_path}: {len(widths)} widths do not fit {interpolation} interpolation")
            if "widths" in expect and interpolation != expect["widths"]:
                fail(f"{prim_path}: widths interpolation {interpolation} != {expect['widths']}")
            seen_widths = True

        primvars = {pv.GetPrimvarName(): pv for pv in UsdGeom.PrimvarsAPI(curves).GetPrimvars()
                    if pv.HasAuthoredValue()}
        for name, primvar in primvars.items():
            values = primvar.ComputeFlattened(rest)
            size = len(values) // max(primvar.GetElementSize(), 1)
            if not fits(curves, size, primvar.GetInterpolation(), rest):
                fail(f"{prim_path}: primvar {name} has {size} values, "
                     f"not a {primvar.GetInterpolation()} size")
        for name, interpolation in expect.get("primvars", {}).items():
            if name not in primvars:
                continue
            seen_primvars.add(name)
            if primvars[name].GetInterpolation() != interpolation:
                fail(f"{prim_path}: primvar {name} is {primvars[name].GetInterpolation()}, "
                     f"expected {interpolation}")

    if "widths" in expect and curves_prims and not seen_widths:
        fail("no curves prim has widths")
    for name in expect.get("primvars", {}):
        if curves_prims and name not in seen_primvars:
            fail(f"no curves prim has primvar {name}")

    # Per-frame attributes: time samples where they change, none elsewhere.
    if "time_varying" in expect:
        for curves in curves_prims:
            sampled = sorted(
                pv.GetPrimvarName() for pv in UsdGeom.PrimvarsAPI(curves).GetPrimvars()
                if pv.GetAttr().GetNumTimeSamples() > 0)
            if sampled != sorted(expect["time_varying"]):
                fail(f"{curves.GetPath()}: time-sampled primvars {sampled}, "
                     f"expected {sorted(expect['time_varying'])}")
    for name, checks in expect.get("frame_values", {}).items():
        for curves in curves_prims:
            primvar = UsdGeom.PrimvarsAPI(curves).GetPrimvar(name)
            if not primvar or primvar.GetAttr().GetNumTimeSamples() == 0:
                fail(f"{curves.GetPath()}: primvar {name} has no time samples")
                continue
            for code, kind, bound in checks:
                if code not in primvar.GetAttr().GetTimeSamples():
                    fail(f"{curves.GetPath()}: primvar {name} has no sample at {code}")
                    continue
                values = list(primvar.Get(Usd.TimeCode(code)))
                low, high = min(values), max(values)
                ok = low > bound if kind == "min_above" else high < bound
                if not ok:
                    fail(f"{curves.GetPath()}: {name} at time code {code} spans "
                         f"{low:.4g}..{high:.4g}, expected {kind} {bound}")
                else:
                    print(f"     {path.name}: {name} at time code {code}: {low:.4g}..{high:.4g}")

    # "prims": {path: {"curves": n, "groom_guide": 0 or 1}}: the curves
    # prims a groom's guides and render strands are written to.
    found = {str(c.GetPath()): c for c in curves_prims}
    for path, wanted in expect.get("prims", {}).items():
        curves = found.get(path)
        if curves is None:
            fail(f"no curves prim {path} (found {sorted(found)})")
            continue
        counts = curves.GetCurveVertexCountsAttr().Get() or []
        if "curves" in wanted and len(counts) != wanted["curves"]:
            fail(f"{path}: {len(counts)} curves, expected {wanted['curves']}")
        if "groom_guide" in wanted:
            primvar = UsdGeom.PrimvarsAPI(curves).GetPrimvar("groom_guide")
            values = primvar.ComputeFlattened() if primvar else None
            if values is None or len(values) != len(counts) or any(
                    v != wanted["groom_guide"] for v in values):
                fail(f"{path}: groom_guide is not {wanted['groom_guide']} on every curve")
    if "prims" in expect and len(found) != len(expect["prims"]):
        fail(f"curves prims {sorted(found)}, expected {sorted(expect['prims'])}")
    if "curves" in expect and total_curves != expect["curves"]:
        fail(f"{total_curves} curves, expected {expect['curves']}")
    if "points" in expect and total_points != expect["points"]:
        fail(f"{total_points} points, expected {expect['points']}")
    if "first_point" in expect and (first_point is None or not close(first_point, expect["first_point"])):
        fail(f"first point {first_point} != {expect['first_point']}")
    if "topology" in expect and not all(
            len(a) == len(b) and close(a, b, 1e-9) for a, b in zip(topology, expect["topology"])) \
            or len(topology) != len(expect.get("topology", topology)):
        fail(f"topology {topology}, expected {expect['topology']}")
    sample_count = len(all_samples or {})
    if "time_samples" in expect and sample_count != expect["time_samples"]:
        fail(f"{sample_count} time samples, expected {expect['time_samples']}")
    for time, index, wanted in expect.get("sample_points", []):
        sample = (all_samples or {}).get(time)
        if sample is None:
            fail(f"no time sample at {time}")
        elif index >= len(sample) or not close(sample[index], wanted):
            got = list(sample[index]) if index < len(sample) else None
            fail(f"point {index} at time {time} is {got}, expected {wanted}")
    return problems


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    directory = Path(sys.argv[1])
    files = sorted(p for p in directory.iterdir() if p.suffix.lower() in EXTENSIONS) \
        if directory.is_dir() else []
    if not files:
        print(f"check_usd: no USD file in {directory}")
        return 1
    failed = 0
    for path in files:
        try:
            problems = check_file(path) + validator_errors(path)
        except Exception as error:  # usd-core raises on unreadable files
            problems = [f"{type(error).__name__}: {error}"]
        if problems:
            failed += 1
            for problem in problems:
                print(f"FAIL {path.name}: {problem}")
        else:
            print(f"ok   {path.name}")
    print(f"check_usd: {len(files) - failed} of {len(files)} USD files pass "
          f"(with {validation_context()[1]} usd-core validators)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
