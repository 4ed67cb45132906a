"""Writes streaming_edges.usdc with usd-core (the reference implementation):
an animated crate file whose time samples a frame-at-a-time reader must pick
as a whole read does: points with a default and samples authored out of
order, two curves prims, a vertex primvar sampled at other codes than the
points (held between them), a uniform primvar with a default, a sample and a
blocked sample, and a translate on each prim. Run: python make_streaming_edges.py"""
from pxr import Usd, UsdGeom, Sdf, Gf

stage = Usd.Stage.CreateNew("streaming_edges.usdc")
stage.SetTimeCodesPerSecond(30)
UsdGeom.SetStageMetersPerUnit(stage, 0.01)
root = UsdGeom.Xform.Define(stage, "/root")
stage.SetDefaultPrim(root.GetPrim())
for k, name in enumerate(["a", "b"]):
    curves = UsdGeom.BasisCurves.Define(stage, f"/root/{name}")
    curves.CreateTypeAttr("linear")
    curves.CreateCurveVertexCountsAttr([3, 2])
    points = curves.CreatePointsAttr()
    points.Set([Gf.Vec3f(0, 0, 0)] * 5)
    for code in [3.0, 1.0, 2.0, 5.0]:
        points.Set([Gf.Vec3f(code + k, i, 0.5 * code) for i in range(5)], code)
    if k == 0:
        api = UsdGeom.PrimvarsAPI(curves)
        wetness = api.CreatePrimvar("wetness", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex)
        for code in [2.5, 0.0, 4.0]:
            wetness.Set([code / 10] * 5, code)
        bonds = api.CreatePrimvar("bond_hydrogen", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.uniform)
        bonds.Set([0.3, 0.4])
        bonds.Set([0.1, 0.2], 2.0)
        bonds.Set(Sdf.ValueBlock(), 3.0)
    curves.CreateWidthsAttr([0.01] * 5)
    UsdGeom.XformCommonAPI(curves).SetTranslate(Gf.Vec3d(1, 0, 0))
stage.GetRootLayer().Save()
