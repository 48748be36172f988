"""Rigs shared by the multi-head tests: 15 deg, 1024 x 1024 px heads (53 arcsec per pixel)."""

from __future__ import annotations

from scipy.spatial.transform import Rotation

from startrack import Camera, CameraRig, RigHead
from startrack.rig import PsfShape

CAMERA = Camera.from_fov(1024, 1024, 15.0)
TURN_X_90 = Rotation.from_euler("x", 90.0, degrees=True)
TURN_Y_90 = Rotation.from_euler("y", 90.0, degrees=True)


def two_heads(b_mount: Rotation = TURN_X_90) -> CameraRig:
    """Head a along body +z, head b turned about body x (90 deg unless given)."""
    return CameraRig([RigHead("a", CAMERA, Rotation.identity()), RigHead("b", CAMERA, b_mount)])


def split_rig(elongation: float = 2.0, minor_px: float = 1.0) -> CameraRig:
    """StarNav II style: two orthogonal fields on one detector, stretched vertically (left) and
    horizontally (right), as in Samaan 2002 Fig. 4."""
    major = elongation * minor_px
    return CameraRig([
        RigHead("left", CAMERA, Rotation.identity(), detector="split", psf=PsfShape(major, minor_px, 90.0)),
        RigHead("right", CAMERA, TURN_X_90, detector="split", psf=PsfShape(major, minor_px, 0.0)),
    ])


def three_heads() -> CameraRig:
    """Three orthogonal heads: a along body +z, b turned about x, c about y."""
    return CameraRig([RigHead("a", CAMERA, Rotation.identity()), RigHead("b", CAMERA, TURN_X_90),
                      RigHead("c", CAMERA, TURN_Y_90)])
