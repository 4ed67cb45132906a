"""Writes exporters/tests/data/unreal_guides.abc with the Alembic library
(alembic3d): an Unreal-style groom of 3 guides and 6 render strands in one
Curves object, in centimetres, Y up, with Unreal's groom attributes typed as
Unreal's importer reads them: groom_guide, groom_id, groom_group_id int32
per curve; groom_closest_guides int32[3] per curve (guide ids);
groom_guide_weights float32[3] per curve; groom_width float per vertex.
Run: python make_unreal_guides.py unreal_guides.abc"""
import math
import sys

import imath
from alembic3d import Abc, AbcGeom

out = sys.argv[1]
S = AbcGeom.GeometryScope


def strand(root, lean, n=6, length=12.0):
    """A strand of n points from root, 12 cm long, curving by lean."""
    pts = []
    for i in range(n):
        s = length * i / (n - 1)
        pts.append((root[0] + lean * s * s / length, root[1] + s, root[2] + 0.1 * s))
    return pts


guide_roots = [(0.0, 10.0, 0.0), (2.0, 10.0, 0.0), (1.0, 10.0, 1.7)]
guides = [strand(r, 0.3 * (k + 1)) for k, r in enumerate(guide_roots)]
# Render strands: inside the triangle of the guide roots, weights barycentric.
weights = [
    (0.6, 0.3, 0.1),
    (0.2, 0.5, 0.3),
    (0.34, 0.33, 0.33),
    (0.1, 0.1, 0.8),
    (0.5, 0.0, 0.5),
    (1.0, 0.0, 0.0),
]
render = []
for w in weights:
    pts = []
    for i in range(6):
        pts.append(tuple(sum(w[k] * guides[k][i][c] for k in range(3)) for c in range(3)))
    render.append(pts)
strands = guides + render
counts = [len(s) for s in strands]
points = [p for s in strands for p in s]
guide_flags = [1, 1, 1] + [0] * len(render)
ids = list(range(len(strands)))
closest = [[g, g, g] for g in range(3)] + [[0, 1, 2] for _ in render]
guide_weights = [[1.0, 0.0, 0.0] for _ in range(3)] + [list(w) for w in weights]
widths = [0.008 * (1.0 - 0.5 * (i % 6) / 5.0) for i in range(len(points))]


def v3(ps):
    a = imath.V3fArray(len(ps))
    for i, p in enumerate(ps):
        a[i] = imath.V3f(*p)
    return a


def ints(vals):
    a = imath.IntArray(len(vals))
    for i, x in enumerate(vals):
        a[i] = x
    return a


def floats(vals):
    a = imath.FloatArray(len(vals))
    for i, x in enumerate(vals):
        a[i] = x
    return a


archive = Abc.OArchive(out)
xform = AbcGeom.OXform(archive.getTop(), "groom")
xform.getSchema().set(AbcGeom.XformSample())
curves = AbcGeom.OCurves(xform, "curves")
schema = curves.getSchema()
sample = AbcGeom.OCurvesSchemaSample()
sample.setPositions(v3(points))
sample.setCurvesNumVertices(ints(counts))
sample.setType(AbcGeom.CurveType.kLinear)
sample.setWrap(AbcGeom.CurvePeriodicity.kNonPeriodic)
sample.setBasis(AbcGeom.BasisType.kNoBasis)
sample.setWidths(AbcGeom.OFloatGeomParamSample(floats(widths), S.kVertexScope))
schema.set(sample)
arb = schema.getArbGeomParams()
for name, scope, extent, vals in [
    ("groom_version_major", S.kConstantScope, 1, [1]),
    ("groom_version_minor", S.kConstantScope, 1, [5]),
    ("groom_guide", S.kUniformScope, 1, guide_flags),
    ("groom_id", S.kUniformScope, 1, ids),
    ("groom_group_id", S.kUniformScope, 1, [0] * len(strands)),
    ("groom_closest_guides", S.kUniformScope, 3, [i for c in closest for i in c]),
]:
    p = AbcGeom.OInt32GeomParam(arb, name, False, scope, extent)
    p.set(AbcGeom.OInt32GeomParamSample(ints(vals), scope))
p = AbcGeom.OFloatGeomParam(arb, "groom_guide_weights", False, S.kUniformScope, 3)
p.set(AbcGeom.OFloatGeomParamSample(floats([x for w in guide_weights for x in w]), S.kUniformScope))
p = AbcGeom.OFloatGeomParam(arb, "groom_width", False, S.kVertexScope, 1)
p.set(AbcGeom.OFloatGeomParamSample(floats(widths), S.kVertexScope))
