"""CameraRig / RigHead: construction checks that name the head, and the JSON round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera, CameraRig, RigHead, get_preset
from startrack.errors import InvalidInputError
from startrack.rig import Exclusion, PsfShape

from .rigs import CAMERA, TURN_X_90, split_rig, two_heads


def test_heads_with_the_same_name_are_refused():
    with pytest.raises(InvalidInputError, match="two heads are named 'a'"):
        CameraRig([RigHead("a", CAMERA, Rotation.identity()), RigHead("a", CAMERA, TURN_X_90)])


@pytest.mark.parametrize("mount, words", [
    (np.array([0.0, 0.0, 0.0, 2.0]), "norm 2"),
    (np.diag([1.0, 1.0, -1.0]), "determinant"),
    (np.eye(3) * 1.1, "orthonormal"),
    ("identity", "not a rotation"),
    (np.zeros(5), "shape (5,)"),
])
def test_a_mounting_that_is_not_a_rotation_names_the_head(mount, words):
    with pytest.raises(InvalidInputError, match="head 'b'") as info:
        RigHead("b", CAMERA, mount)
    assert words in str(info.value)


def test_a_quaternion_or_a_matrix_mounting_becomes_a_rotation():
    q = TURN_X_90.as_quat()
    for given in (q, TURN_X_90.as_matrix()):
        head = RigHead("b", CAMERA, given)
        assert (head.rot_cam_from_body * TURN_X_90.inv()).magnitude() < 1e-12
    np.testing.assert_allclose(RigHead("b", CAMERA, TURN_X_90).boresight_body, [0.0, 1.0, 0.0], atol=1e-12)


def test_other_bad_heads_and_rigs():
    with pytest.raises(InvalidInputError, match="head name"):
        RigHead("a=b", CAMERA, Rotation.identity())
    with pytest.raises(InvalidInputError, match="head 'a': centroid_sigma_px"):
        RigHead("a", CAMERA, Rotation.identity(), centroid_sigma_px=0.0)
    with pytest.raises(InvalidInputError, match="at least one head"):
        CameraRig([])
    with pytest.raises(InvalidInputError, match="reference head 'z'"):
        CameraRig([RigHead("a", CAMERA, Rotation.identity())], reference="z")
    with pytest.raises(InvalidInputError, match="give head.*'left'.*a psf"):
        CameraRig([RigHead("left", CAMERA, Rotation.identity(), detector="d"),
                   RigHead("right", CAMERA, TURN_X_90, detector="d", psf=PsfShape(2, 1, 0))])
    small = Camera.from_fov(512, 512, 15.0)
    with pytest.raises(InvalidInputError, match="one image size"):
        CameraRig([RigHead("l", CAMERA, Rotation.identity(), detector="d", psf=PsfShape(2, 1, 90)),
                   RigHead("r", small, TURN_X_90, detector="d", psf=PsfShape(2, 1, 0))])
    with pytest.raises(InvalidInputError, match="sigma_major_px >= sigma_minor_px"):
        PsfShape(1.0, 2.0)
    with pytest.raises(InvalidInputError, match="sun_deg"):
        Exclusion(sun_deg=-1.0)


@pytest.mark.parametrize("value", [None, "x", [], {}, True])
def test_a_centroid_sigma_that_is_not_a_number_is_refused_by_name(value):
    with pytest.raises(InvalidInputError, match="head 'a': centroid_sigma_px must be a positive number"):
        RigHead("a", CAMERA, Rotation.identity(), centroid_sigma_px=value)


@pytest.mark.parametrize("reference", [[], {}, 1])
def test_a_reference_that_is_not_a_head_name_is_refused(reference):
    with pytest.raises(InvalidInputError, match="reference head .* is not in the rig"):
        CameraRig([RigHead("a", CAMERA, Rotation.identity())], reference=reference)


def test_rig_access():
    rig = split_rig()
    assert rig.names == ("left", "right") and len(rig) == 2 and "left" in rig
    assert list(rig.split_detectors()) == ["split"]
    with pytest.raises(InvalidInputError, match="no head named 'x'.*left, right"):
        rig.head("x")


def test_json_round_trip_keeps_cameras_mountings_psf_and_exclusion(tmp_path):
    rig = CameraRig([*split_rig().heads,
                     RigHead("star", get_preset("starnav-i"), Rotation.from_euler("zyx", [10, 20, 30], degrees=True),
                             centroid_sigma_px=0.3, exclusion=Exclusion(45.0, 25.0, 5.0))], reference="star")
    back = CameraRig.load(rig.save(tmp_path / "rig.json"))
    assert back.names == rig.names and back.reference == "star"
    for a, b in zip(rig, back, strict=True):
        assert a.camera == b.camera and a.psf == b.psf and a.exclusion == b.exclusion and a.detector == b.detector
        assert (a.rot_cam_from_body * b.rot_cam_from_body.inv()).magnitude() < 1e-12
        assert a.centroid_sigma_px == b.centroid_sigma_px


def test_json_camera_by_preset_or_profile_file(tmp_path):
    data = two_heads().to_dict()
    (tmp_path / "cam.json").write_text(json.dumps(data["heads"][1]["camera"]))
    data["heads"][0]["camera"] = "starnav-i"
    data["heads"][1]["camera"] = "cam.json"
    (tmp_path / "rig.json").write_text(json.dumps(data))
    rig = CameraRig.load(tmp_path / "rig.json")
    assert rig.head("a").camera == get_preset("starnav-i") and rig.head("b").camera == CAMERA


@pytest.mark.parametrize("edit, words", [
    (lambda d: d["heads"][1]["rot_cam_from_body"].update(qw=3.0), "head 'b': rot_cam_from_body is not a rotation"),
    (lambda d: d["heads"][1].update(name="a"), "two heads are named 'a'"),
    (lambda d: d["heads"][0].update(camera="no-such-camera"), "head 'a': camera 'no-such-camera'"),
    (lambda d: d["heads"][0].update(colour="red"), "head 'a': unknown keys ['colour']"),
    (lambda d: d["heads"][0].pop("rot_cam_from_body"), "head 'a': missing 'rot_cam_from_body'"),
    (lambda d: d.update(extra=1), "unknown rig keys"),
])
def test_bad_rig_files_name_the_file_and_the_head(tmp_path, edit, words):
    data = two_heads().to_dict()
    edit(data)
    path = tmp_path / "rig.json"
    path.write_text(json.dumps(data))
    with pytest.raises(InvalidInputError, match="rig file") as info:
        CameraRig.load(path)
    assert words in str(info.value)
    path.write_text("{not json")
    with pytest.raises(InvalidInputError, match="not valid JSON"):
        CameraRig.load(path)
    path.write_bytes(b"SIMPLE  =                    T \x80\xff")  # an image given as the rig
    with pytest.raises(InvalidInputError, match="is not JSON text: byte 31 is not UTF-8"):
        CameraRig.load(path)
