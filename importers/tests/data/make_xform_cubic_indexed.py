"""Writes importers/tests/data/xform_cubic_indexed.abc with the Alembic
library (alembic3d): an Xform (translate, rotate Y 30 degrees, scale 2) over
cubic B-spline curves animated over 3 frames at 30 fps, with indexed uvs.
Run: python make_xform_cubic_indexed.py OUT.abc"""
import sys, imath
from alembic3d import Abc, AbcGeom, AbcCoreAbstract
a = Abc.OArchive(sys.argv[1])
tsi = a.addTimeSampling(AbcCoreAbstract.TimeSampling(1.0 / 30, 0.0))
x = AbcGeom.OXform(a.getTop(), "rig")
s = AbcGeom.XformSample()
s.setTranslation(imath.V3d(1, 2, 3))
s.setYRotation(30.0)
s.setScale(imath.V3d(2, 2, 2))
x.getSchema().set(s)
c = AbcGeom.OCurves(x, "cubic", Abc.Argument(tsi))
P = imath.V3fArray(8)
for i in range(8): P[i] = imath.V3f(i % 4, i // 4, 0.5 * i)
n = imath.IntArray(2); n[0] = 4; n[1] = 4
uvvals = imath.V2fArray(2); uvvals[0] = imath.V2f(0.1, 0.2); uvvals[1] = imath.V2f(0.3, 0.4)
idx = imath.UnsignedIntArray(2); idx[0] = 1; idx[1] = 0
for f in range(3):
    smp = AbcGeom.OCurvesSchemaSample()
    for i in range(8): P[i] = imath.V3f(i % 4 + f, i // 4, 0.5 * i)
    smp.setPositions(P); smp.setCurvesNumVertices(n)
    smp.setType(AbcGeom.CurveType.kCubic); smp.setBasis(AbcGeom.BasisType.kBsplineBasis); smp.setWrap(AbcGeom.CurvePeriodicity.kNonPeriodic)
    smp.setUVs(AbcGeom.OV2fGeomParamSample(uvvals, idx, AbcGeom.GeometryScope.kUniformScope))
    c.getSchema().set(smp)
