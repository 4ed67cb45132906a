"""Writes the reference files of exporters/tests/data with the Alembic library
(alembic3d): twins of the scenes groombake writes for a two-strand groom, so
tests can compare the object hashes.
Run: python make_reference.py reference_static.abc
     python make_reference.py reference_animated.abc animated
The animated twin: 4 frames at 24 fps from t = 0.5 s, poses A, B, A, A."""
import sys

import imath
from alembic3d import Abc, AbcCoreAbstract, AbcGeom

out = sys.argv[1]
animated = sys.argv[2:] == ["animated"]
# Two strands: 3 and 2 points (already in cm).
points = [(0, 0, 0), (0, 1, 0), (0, 2, 0.5), (1, 0, 0), (1, 1.5, 0)]
counts = [3, 2]
widths = [0.1, 0.09, 0.08, 0.1, 0.05]
uvs = [(0.25, 0.5), (0.75, 0.5)]

archive = Abc.OArchive(out)
ts = archive.addTimeSampling(AbcCoreAbstract.TimeSampling(1.0 / 24.0, 0.5)) if animated else 0
xform = AbcGeom.OXform(archive.getTop(), "groom")
xform.getSchema().set(AbcGeom.XformSample())
curves = AbcGeom.OCurves(xform, "curves", Abc.Argument(ts))
schema = curves.getSchema()

def v3(ps):
    a = imath.V3fArray(len(ps))
    for i, p in enumerate(ps):
        a[i] = imath.V3f(*p)
    return a

n = imath.IntArray(len(counts))
for i, c in enumerate(counts):
    n[i] = c
w = imath.FloatArray(len(widths))
for i, x in enumerate(widths):
    w[i] = x
uv = imath.V2fArray(len(uvs))
for i, x in enumerate(uvs):
    uv[i] = imath.V2f(*x)
poses = [points]
if animated:
    moved = [(x, y + 0.5, z) for (x, y, z) in points]
    poses = [points, moved, points, points]

sample = AbcGeom.OCurvesSchemaSample()
sample.setPositions(v3(points))
sample.setCurvesNumVertices(n)
sample.setType(AbcGeom.CurveType.kLinear)
sample.setWrap(AbcGeom.CurvePeriodicity.kNonPeriodic)
sample.setBasis(AbcGeom.BasisType.kNoBasis)
sample.setWidths(AbcGeom.OFloatGeomParamSample(w, AbcGeom.GeometryScope.kVertexScope))
sample.setUVs(AbcGeom.OV2fGeomParamSample(uv, AbcGeom.GeometryScope.kUniformScope))
schema.set(sample)
for pose in poses[1:]:
    sample.setPositions(v3(pose))
    schema.set(sample)
arb = schema.getArbGeomParams()
def ints(vals):
    a = imath.IntArray(len(vals))
    for i, x in enumerate(vals):
        a[i] = x
    return a
S = AbcGeom.GeometryScope
# Unreal's Alembic groom schema: the version is int16.
def shorts(vals):
    a = imath.ShortArray(len(vals))
    for i, x in enumerate(vals):
        a[i] = x
    return a
for name, vals in [("groom_version_major", [1]), ("groom_version_minor", [5])]:
    p = AbcGeom.OInt16GeomParam(arb, name, False, S.kConstantScope, 1, Abc.Argument(ts))
    for _ in poses:
        p.set(AbcGeom.OInt16GeomParamSample(shorts(vals), S.kConstantScope))
for name, scope, vals in [("groom_guide", S.kUniformScope, [0, 0]), ("groom_group_id", S.kUniformScope, [0, 0])]:
    p = AbcGeom.OInt32GeomParam(arb, name, False, scope, 1, Abc.Argument(ts))
    for _ in poses:
        p.set(AbcGeom.OInt32GeomParamSample(ints(vals), scope))
p = AbcGeom.OV2fGeomParam(arb, "groom_root_uv", False, S.kUniformScope, 1, Abc.Argument(ts))
for _ in poses:
    p.set(AbcGeom.OV2fGeomParamSample(uv, S.kUniformScope))
p = AbcGeom.OFloatGeomParam(arb, "groom_width", False, S.kVertexScope, 1, Abc.Argument(ts))
for _ in poses:
    p.set(AbcGeom.OFloatGeomParamSample(w, S.kVertexScope))
