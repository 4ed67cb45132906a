"""groombake: bakes styled hair grooms from the chemistry of hair.

Grooms are numpy arrays::

    import groombake
    g = groombake.load("groom.abc")            # any format groombake reads
    g.points, g.counts                         # (N, 3) float32, (S,) int32
    g2 = groombake.Groom.from_arrays(g.points * 2, g.counts)
    g2.save("bigger.usdc")

Timelines and bakes::

    t = groombake.Timeline.load("samples/bed_hair.toml")   # or Timeline.from_dict({...})
    report = groombake.bake(t, out="out", progress=print)  # the GIL is released
    report.outputs

Errors: BadInput (bad files, timelines, values; the CLI's exit code 2) and
BakeError (a failure during the work).
"""

from ._groombake import (  # noqa: F401
    BadInput,
    BakeError,
    Groom,
    Report,
    Timeline,
    __version__,
    bake,
    load,
)

__all__ = ["BadInput", "BakeError", "Groom", "Report", "Timeline", "bake", "load", "__version__"]
