#!/usr/bin/env python3
"""Writes the crate (.usdc) composition fixtures of this folder with usd-core.

usage: /work/venv/bin/python tests/data/usd/make_crate_fixtures.py

Each composed .usda fixture is exported as a crate layer by usd-core
(Sdf.Layer.Export) with its arcs pointed at the crate copies of the layers
it names, so the crate reader sees the arc fields (subLayers, references,
payload, inherits, specializes, instanceable) in usd-core's own list-op
encodings. Three more layers test what only crate files can: a crate layer
whose payload is a text layer, a crate reference to a missing file, and a
reference cycle between two crate layers. The outputs are committed; run
this again only to regenerate them (the bytes depend on the usd-core
version, 26.11 here).
"""
from pathlib import Path

from pxr import Sdf

HERE = Path(__file__).resolve().parent

# Text fixture -> its crate copy, with the layers it names renamed alike.
CRATE_COPIES = {
    "reference_internal": [],
    "payload_curves": [],
    "payload_main": ["payload_curves"],
    "sublayer_base": [],
    "sublayer_main": ["sublayer_base"],
    "instancing": [],
    "inherits": [],
    # A reference with a layer offset (offset 1, scale 2) in the crate's
    # SdfReference encoding; it names the text layer_offset_curves.usda.
    "layer_offset_reference": [],
}


def export_crate(stem, renamed):
    layer = Sdf.Layer.FindOrOpen(str(HERE / f"{stem}.usda"))
    copy = Sdf.Layer.CreateAnonymous(".usda")
    copy.TransferContent(layer)
    for other in renamed:
        for spelling in (f"./{other}.usda", f"{other}.usda"):
            copy.UpdateCompositionAssetDependency(spelling, f"./{other}.usdc")
    copy.Export(str(HERE / f"{stem}.usdc"), args={"format": "usdc"})


def layer_from_text(name, text):
    layer = Sdf.Layer.CreateAnonymous(".usda")
    layer.ImportFromString(text)
    layer.Export(str(HERE / name), args={"format": "usdc"})


def main():
    for stem, renamed in CRATE_COPIES.items():
        export_crate(stem, renamed)
    # A crate layer whose payload is a text layer, and a reference to a
    # prim below the defaultPrim.
    layer_from_text(
        "crate_payload_text.usdc",
        """#usda 1.0
(
    defaultPrim = "Character"
    metersPerUnit = 0.01
    upAxis = "Y"
)

def Xform "Character"
{
    def Xform "Head" (
        prepend payload = @./payload_curves.usda@
    )
    {
        double3 xformOp:translate = (0, 160, 0)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }

    def "Beard" (
        append references = @./payload_curves.usdc@</Hair/Strands>
    )
    {
    }
}
""",
    )
    layer_from_text(
        "crate_missing_reference.usdc",
        """#usda 1.0
(
    metersPerUnit = 0.01
)

def Xform "Head" (
    prepend references = @./not_here.usdc@</Hair>
)
{
}
""",
    )
    for this, other in (("a", "b"), ("b", "a")):
        layer_from_text(
            f"crate_cycle_{this}.usdc",
            f"""#usda 1.0
(
    defaultPrim = "{this.upper()}"
)

def "{this.upper()}" (
    references = @./crate_cycle_{other}.usdc@
)
{{
}}
""",
        )


if __name__ == "__main__":
    main()
