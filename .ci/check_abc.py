#!/usr/bin/env python3
"""Checks every .abc file of a directory with the Alembic library itself
(alembic3d, the unofficial Python bindings of Alembic 1.8.12).

Usage: check_abc.py DIR

Every file must open; every Xform must give its matrix; every Curves object
must be readable at every sample: nVertices positive and adding up to the
points of P, the self bounds holding the points, widths one per point, per
curve or one for all, sample times increasing. A sidecar `<file>.expect.json`
(written by tests/integration/util.rs::hand_to_validators) says what the file
must hold; its keys, all optional:

  curves        total number of curves (all Curves objects, sample 0)
  points        total number of points (sample 0)
  samples       number of P samples (the largest over the Curves objects)
  times         the times of those samples, in seconds
  objects       object paths that must exist, e.g. ["/groom", "/groom/curves"]
  basis         "linear" or a cubic basis name ("bezier", "bspline", ...)
  width         scope of the widths: "vertex", "uniform" or "constant"
  unreal_groom  true: Unreal's groom attributes must be in .arbGeomParams
  guides        number of curves with groom_guide = 1 (guides and render
                hair); the render curves must then carry
                groom_closest_guides (int32[3]) and groom_guide_weights
                (float[3]) per curve, weights summing to 1, ids naming guides
  kind          "abc" (ignored: says which validator the file is for)
  scaled        {"of": "other.abc", "by": k}: every point (sample 0) is the
                other file's point times k, to 1e-6 relative (the units
                check: the same groom written in m and in cm)
  frame_values  {name: [[sample, "min_above" or "max_below", bound], ...]}:
                the float .arbGeomParams property's values at that sample
                (a bake's wetness and bond rates, per frame)
  time_varying  the .arbGeomParams properties whose samples change; every
                other one must be constant (stored once)
  curves_per_sample  the number of curves of each sample (of the Curves
                object with the most samples): a topology that changes
                over time, nVertices written per sample

Exits 1 on any failure, and when the directory holds no .abc file.
"""

import json
import math
import sys
from pathlib import Path

from alembic3d import Abc, AbcGeom

UNREAL_ATTRIBUTES = (
    "groom_version_major",
    "groom_version_minor",
    "groom_guide",
    "groom_group_id",
)
BASIS_NAMES = {
    "kNoBasis": "linear",
    "kBezierBasis": "bezier",
    "kBsplineBasis": "bspline",
    "kCatmullromBasis": "catmull_rom",
    "kHermiteBasis": "hermite",
    "kPowerBasis": "power",
}
SCOPE_NAMES = {
    "kVertexScope": "vertex",
    "kVaryingScope": "vertex",
    "kUniformScope": "uniform",
    "kConstantScope": "constant",
}


class Failures:
    def __init__(self):
        self.messages = []

    def add(self, where, message):
        self.messages.append(f"{where}: {message}")


def walk(obj):
    yield obj
    for child in obj.children:
        yield from walk(child)


def check_curves(obj, file_name, failures, totals):
    where = f"{file_name}:{obj.getFullName()}"
    schema = AbcGeom.ICurves(obj, Abc.WrapExistingFlag.kWrapExisting).getSchema()
    samples = schema.getNumSamples()
    if samples < 1:
        failures.add(where, "Curves with no samples")
        return
    sampling = schema.getTimeSampling()
    times = [sampling.getSampleTime(i) for i in range(samples)]
    if any(b <= a for a, b in zip(times, times[1:])):
        failures.add(where, f"sample times do not increase: {times}")
    widths_param = schema.getWidthsParam()
    curves_per_sample = []
    for index in range(samples):
        # By time: the bindings take a Python int as a time too, so
        # ISampleSelector(index) would read sample `index` seconds in.
        selector = Abc.ISampleSelector(float(times[index]))
        sample = schema.getValue(selector)
        counts = list(sample.getCurvesNumVertices())
        positions = sample.getPositions()
        curves_per_sample.append(len(counts))
        if any(c < 1 for c in counts):
            failures.add(where, f"sample {index}: a curve with no vertices")
        if sum(counts) != len(positions):
            failures.add(
                where,
                f"sample {index}: nVertices add up to {sum(counts)} but P has {len(positions)} points",
            )
        bounds = sample.getSelfBounds()
        low, high = bounds.min(), bounds.max()
        outside = [
            tuple(p)
            for p in positions
            if any(
                p[axis] < low[axis] - 1e-4 * max(1.0, abs(p[axis]))
                or p[axis] > high[axis] + 1e-4 * max(1.0, abs(p[axis]))
                for axis in range(3)
            )
        ]
        if outside:
            failures.add(where, f"sample {index}: {len(outside)} points outside .selfBnds, e.g. {outside[0]}")
        if widths_param.valid() and widths_param.getNumSamples() > 0:
            widths = widths_param.getExpandedValue(selector).getVals()
            if len(widths) not in (len(positions), len(counts), 1):
                failures.add(
                    where,
                    f"sample {index}: {len(widths)} widths for {len(counts)} curves and {len(positions)} points",
                )
            if any(not math.isfinite(w) or w < 0 for w in widths):
                failures.add(where, f"sample {index}: a width is negative or not finite")
        if index == 0:
            totals["positions"].extend(tuple(p) for p in positions)
            totals["curves"] += len(counts)
            totals["points"] += len(positions)
            totals["basis"].add(
                "linear"
                if str(sample.getType()) == "kLinear"
                else BASIS_NAMES.get(str(sample.getBasis()), str(sample.getBasis()))
            )
    if samples > totals["samples"]:
        totals["samples"] = samples
        totals["times"] = times
        totals["curves_per_sample"] = curves_per_sample
    if widths_param.valid():
        totals["width"].add(SCOPE_NAMES.get(str(widths_param.getScope()), str(widths_param.getScope())))
    arbitrary = schema.getArbGeomParams()
    names = set()
    if arbitrary.valid():
        names = {arbitrary.getPropertyHeader(i).getName() for i in range(arbitrary.getNumProperties())}
    totals["arbitrary"].append(names)
    for name in sorted(names):
        header = arbitrary.getPropertyHeader(name)
        if header.isArray() and str(header.getDataType()) == "float32_t":
            # alembic3d's ISampleSelector(number) selects by time: sample i
            # is asked for at its time.
            param = AbcGeom.IFloatGeomParam(arbitrary, name)
            param_times = param.getTimeSampling()
            values = [list(param.getExpandedValue(
                Abc.ISampleSelector(param_times.getSampleTime(i))).getVals())
                for i in range(param.getNumSamples())]
            totals["float_params"][name] = values
        if not param_is_constant(arbitrary, name):
            totals["varying"].add(name)
    if "groom_guide" in names:
        count_guides(arbitrary, len(counts), where, failures, totals)


def param_is_constant(arbitrary, name):
    """Whether every sample of a .arbGeomParams property is the same (then
    Alembic stores it once)."""
    header = arbitrary.getPropertyHeader(name)
    if header.isCompound():
        values = Abc.ICompoundProperty(arbitrary, name)
        if not values.getPropertyHeader(".vals"):
            return True
        return Abc.IArrayProperty(values, ".vals").isConstant()
    if header.isArray():
        return Abc.IArrayProperty(arbitrary, name).isConstant()
    return Abc.IScalarProperty(arbitrary, name).isConstant()


def int_values(arbitrary, name):
    param = AbcGeom.IInt32GeomParam(arbitrary, name)
    return param, list(param.getExpandedValue(Abc.ISampleSelector(0)).getVals())


def count_guides(arbitrary, curves, where, failures, totals):
    """Guides and render curves of Unreal's split, with their links."""
    _, flags = int_values(arbitrary, "groom_guide")
    if len(flags) != curves:
        failures.add(where, f"groom_guide has {len(flags)} values for {curves} curves")
        return
    guides = [i for i, f in enumerate(flags) if f]
    totals["guides"] += len(guides)
    if len(guides) in (0, curves):
        return
    names = {arbitrary.getPropertyHeader(i).getName() for i in range(arbitrary.getNumProperties())}
    if not {"groom_closest_guides", "groom_guide_weights", "groom_id"} <= names:
        failures.add(where, "render curves without groom_closest_guides / groom_guide_weights / groom_id")
        return
    param, closest = int_values(arbitrary, "groom_closest_guides")
    weights_param = AbcGeom.IFloatGeomParam(arbitrary, "groom_guide_weights")
    weights = list(weights_param.getExpandedValue(Abc.ISampleSelector(0)).getVals())
    _, ids = int_values(arbitrary, "groom_id")
    if param.getArrayExtent() != 3 or weights_param.getArrayExtent() != 3:
        failures.add(where, "groom_closest_guides / groom_guide_weights are not of array extent 3")
        return
    if len(closest) != 3 * curves or len(weights) != 3 * curves:
        failures.add(where, f"{len(closest)} closest guides, {len(weights)} weights for {curves} curves")
        return
    guide_ids = {ids[i] for i in guides}
    for c in range(curves):
        if flags[c]:
            continue
        if any(closest[3 * c + k] not in guide_ids for k in range(3)):
            failures.add(where, f"curve {c}: closest guides {closest[3 * c:3 * c + 3]} are not guide ids")
            return
        if abs(sum(weights[3 * c:3 * c + 3]) - 1.0) > 1e-4:
            failures.add(where, f"curve {c}: guide weights {weights[3 * c:3 * c + 3]} do not sum to 1")
            return


def sample_zero_positions(path):
    archive = Abc.IArchive(str(path))
    positions = []
    for obj in walk(archive.getTop()):
        if AbcGeom.ICurves.matches(obj.getMetaData()):
            schema = AbcGeom.ICurves(obj, Abc.WrapExistingFlag.kWrapExisting).getSchema()
            positions.extend(tuple(p) for p in schema.getValue(Abc.ISampleSelector(0)).getPositions())
    return positions


def check_scaled(path, positions, scaled, failures):
    other_path = path.with_name(scaled["of"])
    factor = scaled["by"]
    where = f"{path.name} vs {other_path.name}"
    if not other_path.exists():
        failures.add(where, "the file to compare with is missing")
        return
    other = sample_zero_positions(other_path)
    if len(other) != len(positions):
        failures.add(where, f"{len(positions)} points against {len(other)}")
        return
    worst = 0.0
    for mine, theirs in zip(positions, other):
        for a, b in zip(mine, theirs):
            want = b * factor
            worst = max(worst, abs(a - want) / max(abs(want), 1e-30))
    if worst > 1e-6:
        failures.add(where, f"points are not the other's times {factor}: worst relative error {worst:.3g}")
    else:
        print(f"ok   {where}: points are the other's times {factor} (worst relative error {worst:.3g})")


def check_file(path, failures):
    name = path.name
    try:
        archive = Abc.IArchive(str(path))
    except Exception as error:  # the library raises plain RuntimeErrors
        failures.add(name, f"alembic3d cannot open it: {error}")
        return
    totals = {
        "curves": 0,
        "points": 0,
        "samples": 0,
        "curves_per_sample": [],
        "times": [],
        "basis": set(),
        "width": set(),
        "arbitrary": [],
        "positions": [],
        "guides": 0,
        "float_params": {},
        "varying": set(),
    }
    paths = set()
    curves_objects = 0
    try:
        for obj in walk(archive.getTop()):
            paths.add(obj.getFullName())
            metadata = obj.getMetaData()
            if AbcGeom.IXform.matches(metadata):
                xform = AbcGeom.IXform(obj, Abc.WrapExistingFlag.kWrapExisting).getSchema()
                for index in range(max(1, xform.getNumSamples())):
                    xform.getValue(Abc.ISampleSelector(index)).getMatrix()
            elif AbcGeom.ICurves.matches(metadata):
                curves_objects += 1
                check_curves(obj, name, failures, totals)
    except Exception as error:
        failures.add(name, f"alembic3d fails reading it: {error}")
        return
    if curves_objects == 0:
        failures.add(name, "no Curves object")
    expect_path = path.with_name(path.name + ".expect.json")
    if not expect_path.exists():
        print(f"ok   {name}: {totals['curves']} curves, {totals['points']} points, "
              f"{totals['samples']} samples (no expectations)")
        return
    expect = json.loads(expect_path.read_text())
    before = len(failures.messages)
    for key in ("curves", "points", "samples"):
        if key in expect and expect[key] != totals[key]:
            failures.add(name, f"{key}: expected {expect[key]}, found {totals[key]}")
    if "curves_per_sample" in expect and expect["curves_per_sample"] != totals["curves_per_sample"]:
        failures.add(name, f"curves per sample: expected {expect['curves_per_sample']}, "
                           f"found {totals['curves_per_sample']}")
    if "times" in expect:
        found = totals["times"]
        wanted = expect["times"]
        if len(found) != len(wanted) or any(abs(a - b) > 1e-6 for a, b in zip(found, wanted)):
            failures.add(name, f"times: expected {wanted}, found {found}")
    for wanted in expect.get("objects", []):
        if wanted not in paths:
            failures.add(name, f"object {wanted} missing (found {sorted(paths)})")
    if "basis" in expect and totals["basis"] != {expect["basis"]}:
        failures.add(name, f"basis: expected {expect['basis']}, found {sorted(totals['basis'])}")
    if "width" in expect and totals["width"] != {expect["width"]}:
        failures.add(name, f"width: expected {expect['width']}, found {sorted(totals['width'])}")
    if expect.get("unreal_groom"):
        for names in totals["arbitrary"]:
            missing = [a for a in UNREAL_ATTRIBUTES if a not in names]
            if missing:
                failures.add(name, f"Unreal groom attributes missing from .arbGeomParams: {missing}")
    if "scaled" in expect:
        check_scaled(path, totals["positions"], expect["scaled"], failures)
    if "guides" in expect and expect["guides"] != totals["guides"]:
        failures.add(name, f"guides: expected {expect['guides']}, found {totals['guides']}")
    if "time_varying" in expect and totals["varying"] != set(expect["time_varying"]):
        failures.add(name, f"time-varying .arbGeomParams {sorted(totals['varying'])}, "
                           f"expected {sorted(expect['time_varying'])}")
    for param, checks in expect.get("frame_values", {}).items():
        samples = totals["float_params"].get(param)
        if not samples:
            failures.add(name, f"no float .arbGeomParams property {param}")
            continue
        for index, kind, bound in checks:
            if index >= len(samples) or not samples[index]:
                failures.add(name, f"{param} has no sample {index} ({len(samples)} samples)")
                continue
            low, high = min(samples[index]), max(samples[index])
            ok = low > bound if kind == "min_above" else high < bound
            if not ok:
                failures.add(name, f"{param} at sample {index} spans {low:.4g}..{high:.4g}, "
                                   f"expected {kind} {bound}")
            else:
                print(f"     {name}: {param} at sample {index}: {low:.4g}..{high:.4g}")
    known = {
        "kind", "curves", "points", "samples", "times", "objects", "basis", "width",
        "unreal_groom", "scaled", "guides", "frame_values", "time_varying", "curves_per_sample",
    }
    unknown = set(expect) - known
    if unknown:
        failures.add(name, f"unknown expectation keys {sorted(unknown)}")
    if len(failures.messages) == before:
        print(f"ok   {name}: {totals['curves']} curves, {totals['points']} points, "
              f"{totals['samples']} samples, as expected")


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    directory = Path(sys.argv[1])
    files = sorted(directory.rglob("*.abc"))
    if not files:
        print(f"check_abc: no .abc file in {directory}", file=sys.stderr)
        return 1
    failures = Failures()
    for path in files:
        check_file(path, failures)
    for message in failures.messages:
        print(f"FAIL {message}")
    print(f"check_abc: {len(files)} files, {len(failures.messages)} failures")
    return 1 if failures.messages else 0


if __name__ == "__main__":
    sys.exit(main())
