"""Writes the USD fixtures of the importer tests with usd-core (the
reference implementation) and, beside each, the world-space points and
attributes usd-core computes, as JSON. Run: python make_fixtures.py"""
import json
from pxr import Usd, UsdGeom, Sdf, Gf, Vt

def build(path):
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    stage.SetTimeCodesPerSecond(30)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(3)
    root = UsdGeom.Xform.Define(stage, "/Root")
    stage.SetDefaultPrim(root.GetPrim())
    root.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
    root.AddRotateXYZOp().Set(Gf.Vec3f(10, 20, 30))
    child = UsdGeom.Xform.Define(stage, "/Root/Child")
    child.AddOrientOp().Set(Gf.Quatf(0.9238795, 0.0, 0.3826834, 0.0))
    child.AddScaleOp().Set(Gf.Vec3f(2, 2, 2))
    m = Gf.Matrix4d().SetTranslate(Gf.Vec3d(0.5, 0, 0))
    child.AddTransformOp(opSuffix="extra").Set(m)
    curves = UsdGeom.BasisCurves.Define(stage, "/Root/Child/Curves")
    strands, per = 20, 10
    counts = [per] * strands
    pts = [Gf.Vec3f(s * 0.1, i * 0.25, (s * i) % 7 * 0.01) for s in range(strands) for i in range(per)]
    curves.CreateCurveVertexCountsAttr(counts)
    curves.CreatePointsAttr(pts)
    curves.CreateTypeAttr(UsdGeom.Tokens.linear)
    pa = curves.GetPointsAttr()
    for t in (1, 2, 3):
        pa.Set([Gf.Vec3f(p[0] + t, p[1], p[2]) for p in pts], t)
    curves.CreateWidthsAttr([float(i % 3) for i in range(strands * per)])  # integral -> 'i' code
    curves.SetWidthsInterpolation(UsdGeom.Tokens.vertex)
    api = UsdGeom.PrimvarsAPI(curves)
    api.CreatePrimvar("wetness", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex).Set(
        [0.25 * (i % 4) + 0.1 for i in range(strands * per)])  # few distinct -> 't' lookup
    api.CreatePrimvar("clump", Sdf.ValueTypeNames.IntArray, UsdGeom.Tokens.uniform).Set(
        [s * 3 + 100 for s in range(strands)])  # >= 16 ints -> compressed
    api.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.uniform).Set(
        [Gf.Vec2f(s / 20.0, 1 - s / 20.0) for s in range(strands)])
    api.CreatePrimvar("tint", Sdf.ValueTypeNames.Color3fArray, UsdGeom.Tokens.constant).Set(
        [Gf.Vec3f(0.5, 0.25, 0.125)])
    idx = api.CreatePrimvar("level", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.uniform)
    idx.Set([1.5, 2.5])
    idx.SetIndices(Vt.IntArray([s % 2 for s in range(strands)]))
    api.CreatePrimvar("pair", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex, 2).Set(
        [float(i) for i in range(2 * strands * per)])  # elementSize 2: skipped
    second = UsdGeom.BasisCurves.Define(stage, "/Root/Other")
    second.CreateCurveVertexCountsAttr([4])
    second.CreatePointsAttr([Gf.Vec3f(0, 0, i) for i in range(4)])
    second.CreateTypeAttr(UsdGeom.Tokens.cubic)
    second.CreateBasisAttr(UsdGeom.Tokens.bspline)
    stage.GetRootLayer().Save()
    return stage

def expected(stage):
    out = {"meters_per_unit": UsdGeom.GetStageMetersPerUnit(stage),
           "up_axis": UsdGeom.GetStageUpAxis(stage), "prims": []}
    for prim in stage.Traverse():
        if prim.GetTypeName() != "BasisCurves":
            continue
        c = UsdGeom.BasisCurves(prim)
        xf = UsdGeom.Xformable(prim)
        times = c.GetPointsAttr().GetTimeSamples()
        m = xf.ComputeLocalToWorldTransform(Usd.TimeCode.Default())
        world = lambda pts: [list(m.Transform(Gf.Vec3d(p))) for p in pts]
        out["prims"].append({
            "path": str(prim.GetPath()),
            "counts": list(c.GetCurveVertexCountsAttr().Get()),
            "points": world(c.GetPointsAttr().Get()),
            "samples": [[t, world(c.GetPointsAttr().Get(t))] for t in times],
            "widths": list(c.GetWidthsAttr().Get() or []),
            "primvars": {pv.GetPrimvarName(): [list(v) if hasattr(v, "__len__") else v for v in pv.ComputeFlattened()]
                         for pv in UsdGeom.PrimvarsAPI(prim).GetPrimvars() if pv.HasValue()},
        })
    return out

def rounded(x):
    """9 decimals: enough for f32 points, short enough to keep the file small."""
    if isinstance(x, float):
        return round(x, 9)
    if isinstance(x, list):
        return [rounded(v) for v in x]
    if isinstance(x, dict):
        return {k: rounded(v) for k, v in x.items()}
    return x


for ext in ("usdc", "usda"):
    stage = build(f"reference.{ext}")
    with open("reference.json", "w") as f:
        json.dump(rounded(expected(stage)), f, separators=(",", ":"))

# Blender's file as usd-core writes it in crate form (inlined vectors,
# strings, dictionaries, token arrays).
Sdf.Layer.FindOrOpen("../../../tests/data/blender501_hair.usda").Export(
    "blender501_hair_by_usd_core.usdc")
