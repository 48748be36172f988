"""The colour rule of the detector is the one rule of :mod:`startrack.io._channels` (R + G + B by
default, a chosen plane otherwise), re-exported here for ``startrack.detect.to_single_channel``."""

from __future__ import annotations

from ..io import to_single_channel

__all__ = ["to_single_channel"]
