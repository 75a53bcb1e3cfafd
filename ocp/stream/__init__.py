"""Streaming reversal shaper: actuator-aware thrust references in real time (issue 18).

``StreamShaper(params, stream_options(current=..., voltage=..., regularity=..., delay=..., dt=...))``;
``push(t, thrust)`` once per sample returns a :class:`StreamSample`. :func:`shape_profile` runs a
whole array through it (tests, benches). Roles: ``options`` (what the user sets), ``preview`` (the
look-ahead tracker's design), ``governor`` (limits), ``inverse`` (exact feed-forward), ``shaper``
(the per-sample step), ``trace`` (whole-array runs), ``blend`` (the analytic-reversal alternative
kept for comparison), ``codegen`` (the step as C).
"""

from ocp.stream.options import StreamOptions, stream_options
from ocp.stream.shaper import StreamSample, StreamShaper
from ocp.stream.trace import StreamTrace, shape_profile

__all__ = ["StreamOptions", "StreamSample", "StreamShaper", "StreamTrace", "shape_profile", "stream_options"]
