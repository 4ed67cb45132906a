from ._groombake import (
    BadInput as BadInput,
    BakeError as BakeError,
    Groom as Groom,
    Report as Report,
    Timeline as Timeline,
    __version__ as __version__,
    bake as bake,
    load as load,
)
