#!/usr/bin/env python3
"""Checks guide caches (`[[export]] cache = "guides"`) with the readers
themselves: usd-core for .usdc/.usd, the Alembic library (alembic3d) for
.abc.

Usage: check_guide_cache.py DIR

For every `<name>.guide_cache.json` in DIR (written by
tests/integration/guide_cache.rs), whose keys are

  cache      the guide cache's file name (in DIR)
  full       the file name of the full cache of the same bake (in DIR)
  guides     number of guide curves
  render     number of render curves
  samples    number of frames
  tolerance  the largest mean distance allowed between the interpolated
             and the full cache's render hair, in strand lengths

it opens both files and checks that:
- the guides animate (a sample per frame, the last differs from the
  first) and are the full cache's guides at every frame;
- the render hair is at rest (one sample, no time samples), the full
  cache's first frame, with per-curve
  closest guides (three guide indices) and weights (three, in [0, 1],
  summing to 1);
- deforming the rest render hair by its guides' motion (each render vertex
  moves by the weighted motion of its guides at the same fraction of their
  length) comes near the full cache's render hair at every frame, within
  `tolerance`. This is a reader's interpolation, not groombake's own
  (which turns the guides' shapes in their root frames), so it is near,
  not equal (its largest errors, at the tips of strands whose guides
  swing apart, are printed); tests/integration/guide_cache.rs checks that
  groombake's interpolation of the cache gives the full cache's render
  hair to 1e-6 m;
and prints both files' bytes per vertex-frame.

Exits 1 on any failure, and when DIR holds no guide cache.
"""

import json
import sys
from pathlib import Path

import numpy as np


def strands(counts, points):
    """The points of each strand."""
    out, start = [], 0
    for n in counts:
        out.append(points[start:start + n])
        start += n
    return out


def read_usd(path):
    """(guide counts, guide frames, render counts, render frames, closest,
    weights, render time samples) of a USD file with `guides` and `render`
    prims."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    root = stage.GetDefaultPrim()
    guides = UsdGeom.BasisCurves(root.GetChild("guides"))
    render = UsdGeom.BasisCurves(root.GetChild("render"))
    times = guides.GetPointsAttr().GetTimeSamples()
    guide_frames = [np.array(guides.GetPointsAttr().Get(t), dtype=np.float64) for t in times]
    render_attr = render.GetPointsAttr()
    render_times = render_attr.GetTimeSamples()
    render_frames = [np.array(render_attr.Get(t), dtype=np.float64) for t in render_times] or [
        np.array(render_attr.Get(), dtype=np.float64)
    ]
    primvars = UsdGeom.PrimvarsAPI(render.GetPrim())
    closest = np.array(primvars.GetPrimvar("groom_closest_guides").Get(), dtype=np.int64)
    weights = np.array(primvars.GetPrimvar("groom_guide_weights").Get(), dtype=np.float64)
    return {
        "guide_counts": list(guides.GetCurveVertexCountsAttr().Get()),
        "guide_frames": guide_frames,
        "render_counts": list(render.GetCurveVertexCountsAttr().Get()),
        "render_frames": render_frames,
        "render_time_samples": len(render_times),
        "closest": closest,
        "weights": weights,
    }


def read_abc(path):
    """The same of an Alembic file: guides and render curves told apart by
    `groom_guide` (in one object or several), render links from
    `groom_closest_guides` (guide `groom_id`s) and `groom_guide_weights`."""
    from alembic3d import Abc, AbcGeom

    archive = Abc.IArchive(str(path))
    parts = []

    def walk(obj):
        yield obj
        for child in obj.children:
            yield from walk(child)

    for obj in walk(archive.getTop()):
        if not AbcGeom.ICurves.matches(obj.getMetaData()):
            continue
        schema = AbcGeom.ICurves(obj, Abc.WrapExistingFlag.kWrapExisting).getSchema()
        sampling = schema.getTimeSampling()
        n = schema.getNumSamples()
        frames = []
        counts = None
        for i in range(n):
            sample = schema.getValue(Abc.ISampleSelector(float(sampling.getSampleTime(i))))
            counts = list(sample.getCurvesNumVertices())
            frames.append(np.array([tuple(p) for p in sample.getPositions()], dtype=np.float64))
        arbitrary = schema.getArbGeomParams()

        def ints(name):
            param = AbcGeom.IInt32GeomParam(arbitrary, name)
            return np.array(list(param.getExpandedValue(Abc.ISampleSelector(0)).getVals()), dtype=np.int64)

        weights = AbcGeom.IFloatGeomParam(arbitrary, "groom_guide_weights")
        parts.append({
            "counts": counts,
            "frames": frames,
            "guide": ints("groom_guide"),
            "id": ints("groom_id"),
            "closest": ints("groom_closest_guides").reshape(-1, 3),
            "weights": np.array(list(weights.getExpandedValue(Abc.ISampleSelector(0)).getVals()),
                                dtype=np.float64).reshape(-1, 3),
        })
    samples = max(len(p["frames"]) for p in parts)

    def gather(is_guide):
        counts, frames, ids, closest, weights, time_samples = [], [], [], [], [], 0
        per_frame = [[] for _ in range(samples)]
        for part in parts:
            offsets = np.concatenate([[0], np.cumsum(part["counts"])])
            keep = [c for c in range(len(part["counts"])) if bool(part["guide"][c]) == is_guide]
            if not keep:
                continue
            time_samples = max(time_samples, len(part["frames"]))
            for f in range(samples):
                # A part with one sample holds at every frame.
                points = part["frames"][min(f, len(part["frames"]) - 1)]
                per_frame[f].extend(points[offsets[c]:offsets[c + 1]] for c in keep)
            counts.extend(part["counts"][c] for c in keep)
            ids.extend(part["id"][c] for c in keep)
            closest.extend(part["closest"][c] for c in keep)
            weights.extend(part["weights"][c] for c in keep)
        frames = [np.concatenate(f) for f in per_frame]
        return counts, frames, ids, np.array(closest), np.array(weights), time_samples

    guide_counts, guide_frames, guide_ids, _, _, _ = gather(True)
    render_counts, render_frames, _, closest, weights, render_samples = gather(False)
    index_of = {int(i): k for k, i in enumerate(guide_ids)}
    closest = np.array([[index_of.get(int(i), -1) for i in row] for row in closest], dtype=np.int64)
    return {
        "guide_counts": guide_counts,
        "guide_frames": guide_frames,
        "render_counts": render_counts,
        "render_frames": render_frames if render_samples > 1 else render_frames[:1],
        "render_time_samples": render_samples if render_samples > 1 else 0,
        "closest": closest,
        "weights": weights,
    }


def read(path):
    return read_abc(path) if path.suffix == ".abc" else read_usd(path)


def at_fraction(strand, u):
    """Points at fractions u of a strand, by vertex index (linear)."""
    f = u * (len(strand) - 1)
    i = np.minimum(np.floor(f).astype(int), len(strand) - 2)
    t = (f - i)[:, None]
    return strand[i] * (1 - t) + strand[i + 1] * t


def along_guides(guides, n):
    """Each guide's points at n even fractions of its length: (guides, n, 3)."""
    u = np.linspace(0.0, 1.0, n)
    return np.stack([at_fraction(g, u) for g in guides])


def deformation_errors(cache, full, samples, closest, weights):
    """Per render vertex and frame, the distance from the rest render hair
    moved the simplest way a reader does it (each vertex at fraction u of
    its strand moves by the weighted motion of its guides' points at u) to
    the full cache's render hair, in strand lengths."""
    counts = np.array(cache["render_counts"])
    offsets = np.concatenate([[0], np.cumsum(counts)])
    rest_points = cache["render_frames"][0]
    guide_rest = strands(cache["guide_counts"], cache["guide_frames"][0])
    errors = []
    for n in sorted(set(counts.tolist())):
        which = np.flatnonzero(counts == n)
        index = offsets[which][:, None] + np.arange(n)[None, :]
        rest = rest_points[index]
        lengths = np.maximum(np.linalg.norm(np.diff(rest, axis=1), axis=2).sum(axis=1), 1e-12)
        at_rest = along_guides(guide_rest, n)
        for f in range(samples):
            now = along_guides(strands(cache["guide_counts"], cache["guide_frames"][f]), n)
            moved = rest.copy()
            for k in range(3):
                g = closest[which, k]
                moved += weights[which, k][:, None, None] * (now[g] - at_rest[g])
            want = full["render_frames"][f][index]
            errors.append((np.linalg.norm(moved - want, axis=2) / lengths[:, None]).ravel())
    return np.concatenate(errors)


def check(spec, directory, failures):
    cache_path = directory / spec["cache"]
    full_path = directory / spec["full"]
    name = cache_path.name
    before = len(failures)
    try:
        cache = read(cache_path)
        full = read(full_path)
    except Exception as error:  # the readers raise plain RuntimeErrors
        failures.append(f"{name}: cannot be read: {error}")
        return
    guides, render, samples = spec["guides"], spec["render"], spec["samples"]
    if len(cache["guide_counts"]) != guides or len(cache["render_counts"]) != render:
        failures.append(f"{name}: {len(cache['guide_counts'])} guides, {len(cache['render_counts'])} "
                        f"render curves; want {guides}, {render}")
        return
    if len(cache["guide_frames"]) != samples or len(full["render_frames"]) != samples:
        failures.append(f"{name}: {len(cache['guide_frames'])} guide samples, full cache "
                        f"{len(full['render_frames'])}; want {samples}")
        return
    if np.array_equal(cache["guide_frames"][0], cache["guide_frames"][-1]):
        failures.append(f"{name}: the guides do not move")
    if cache["render_time_samples"] != 0 or len(cache["render_frames"]) != 1:
        failures.append(f"{name}: the render hair has {cache['render_time_samples']} time samples, want none")
    closest, weights = cache["closest"], cache["weights"]
    if closest.shape != (render, 3) or weights.shape != (render, 3):
        failures.append(f"{name}: closest guides {closest.shape}, weights {weights.shape}; want ({render}, 3)")
        return
    if closest.min() < 0 or closest.max() >= guides:
        failures.append(f"{name}: a closest guide is not a guide")
        return
    if weights.min() < 0 or weights.max() > 1 or np.abs(weights.sum(axis=1) - 1).max() > 1e-4:
        failures.append(f"{name}: weights outside [0, 1] or not summing to 1")
    for f in range(samples):
        if not np.allclose(cache["guide_frames"][f], full["guide_frames"][f], atol=0, rtol=0):
            failures.append(f"{name}: frame {f}: the guides differ from the full cache's")
            break
    if not np.array_equal(cache["render_frames"][0], full["render_frames"][0]):
        failures.append(f"{name}: the rest render hair is not the full cache's first frame")
    errors = deformation_errors(cache, full, samples, closest, weights)
    mean, p99, worst = float(errors.mean()), float(np.percentile(errors, 99)), float(errors.max())
    if mean > spec["tolerance"]:
        failures.append(f"{name}: interpolated render hair is {mean:.4f} strand lengths from the full "
                        f"cache's on average, {p99:.4f} at the 99th percentile; "
                        f"tolerance {spec['tolerance']}")
    guide_vertices = sum(cache["guide_counts"])
    render_vertices = sum(cache["render_counts"])
    vertex_frames = (guide_vertices + render_vertices) * samples
    cache_size, full_size = cache_path.stat().st_size, full_path.stat().st_size
    status = "ok  " if len(failures) == before else "FAIL"
    print(f"{status} {name}: {guides} guides animated over {samples} frames, {render} render curves at rest; "
          f"interpolated vs full: mean {mean:.5f}, 99th percentile {p99:.4f}, largest {worst:.4f} "
          f"strand lengths; "
          f"{cache_size / vertex_frames:.2f} B per vertex-frame vs {full_size / vertex_frames:.2f} "
          f"({full_path.name}), ratio {cache_size / full_size:.3f}")


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    directory = Path(sys.argv[1])
    specs = sorted(directory.glob("*.guide_cache.json"))
    if not specs:
        print(f"no guide cache in {directory}")
        return 1
    failures = []
    for path in specs:
        check(json.loads(path.read_text()), directory, failures)
    for failure in failures:
        print(f"FAIL {failure}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
