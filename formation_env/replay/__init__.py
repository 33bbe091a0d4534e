"""Episode replay: logs (:class:`EpisodeLog`, :class:`EpisodeRecorder`), Tacview ACMI 2.1 export
and parsing (:mod:`.acmi`), animated GIF/MP4 (:mod:`.animation`) and the shared formation drawing
(:mod:`.view`, also used by ``env.render()``). Importing this package selects no matplotlib backend."""

from .acmi import AcmiRecording, acmi_text, parse_acmi, write_acmi
from .log import EpisodeLog, EpisodeRecorder

__all__ = ["EpisodeLog", "EpisodeRecorder", "acmi_text", "write_acmi", "parse_acmi", "AcmiRecording",
           "write_animation"]


def write_animation(*args, **kw):
    """See :func:`formation_env.replay.animation.write_animation` (imports matplotlib lazily)."""
    from .animation import write_animation as _w

    return _w(*args, **kw)
