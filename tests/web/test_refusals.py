"""Every refusal of the server, through a real server: 400, 403, 404, 413 (while streaming), 415
(from the content), 416 (a Range past a result file's end), 422 (options, absurd dimensions from the
header), and the server keeps serving after each one (429 and 409 are in test_runner.py, with the
queue they need)."""

from __future__ import annotations

import io
import json
import re
import struct
import zlib
from pathlib import Path

import pytest
from astropy.io import fits

LIMIT_BYTES = 8_000_000  # the session server's --max-upload-mb 8
SOURCES = Path(__file__).resolve().parents[2] / "src" / "startrack"


def still_serving(server) -> None:
    assert server.client.get("/api/status").status_code == 200


def png_header(width: int, height: int) -> bytes:
    """A PNG whose IHDR declares ``width`` x ``height`` (8-bit grey) with a token IDAT: what a
    decompression bomb looks like before it is decoded."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + chunk(b"IEND", b""))


def fits_header_only(width: int, height: int) -> bytes:
    header = fits.Header([("SIMPLE", True), ("BITPIX", 16), ("NAXIS", 2), ("NAXIS1", width), ("NAXIS2", height)])
    return header.tostring().encode("ascii")


def post_file(server, content: bytes, name: str, options: dict | None = None):
    data = {} if options is None else {"options": json.dumps(options)}
    return server.client.post("/api/jobs", files={"file": (name, io.BytesIO(content))}, data=data)


def multipart_head(server, extra: str) -> bytes:
    return (f"POST /api/jobs HTTP/1.1\r\nHost: {server.host}:{server.port}\r\n"
            f"Content-Type: multipart/form-data; boundary=B0UND\r\n{extra}\r\n").encode()


def test_413_from_the_declared_length_before_any_body_is_sent(server):
    status, body = server.raw_request(multipart_head(server, f"Content-Length: {LIMIT_BYTES + 1}\r\n"))
    assert status == 413
    assert "limit is 8 MB" in body["error"] and str(LIMIT_BYTES + 1) in body["error"]
    still_serving(server)


def test_413_while_a_chunked_body_streams_before_its_end(server):
    part_head = b'--B0UND\r\nContent-Disposition: form-data; name="file"; filename="big.fits"\r\n\r\n'
    chunk = b"\x00" * 1_000_000
    chunks = [part_head] + [chunk] * 9  # 9 MB of file data, and the body's last chunk never sent
    framed = [f"{len(c):x}\r\n".encode() + c + b"\r\n" for c in chunks]
    status, body = server.raw_request(multipart_head(server, "Transfer-Encoding: chunked\r\n"), framed)
    assert status == 413 and "more than 8000000 bytes arrived" in body["error"]
    still_serving(server)


NOT_AN_IMAGE = "is not FITS, XISF, PNG, JPEG, TIFF, HEIC, WebP, AVIF, BMP or camera RAW"


@pytest.mark.parametrize(("content", "name", "said"), [
    (b"just some text, not an image\n" * 10, "notes.png", NOT_AN_IMAGE),
    (b"GIF89a" + b"\x00" * 200, "anim.jpg", NOT_AN_IMAGE),
    (b"\x89PNG\r\n\x1a\n" + b"garbage" * 30, "broken.png", "its header cannot be read"),
    (b"SIMPLE  =                    T" + b" " * 50 + b"NAXIS   = nonsense", "broken.fits", "header cannot be read"),
])
def test_415_from_the_content_not_the_name(server, content, name, said):
    response = post_file(server, content, name)
    assert response.status_code == 415
    assert said in response.json()["error"] and response.json()["field"] == "file"
    still_serving(server)


def test_a_page_form_refusal_is_an_error_page_with_the_same_status(server):
    response = server.client.post("/upload", files={"file": ("notes.png", b"just some text")})
    assert response.status_code == 415 and "text/html" in response.headers["content-type"]
    assert NOT_AN_IMAGE in response.text
    response = server.client.post("/upload", files={"file": ("roof.jpg", b"\xff\xd8\xff")},
                                  data={"fov_mode": "fov", "fov_deg": "ten"})
    assert response.status_code == 422 and "options.fov_deg" in response.text
    still_serving(server)


def test_415_for_a_body_that_is_not_multipart(server):
    response = server.client.post("/api/jobs", json={"file": "roof.jpg"})
    assert response.status_code == 415 and "multipart/form-data" in response.json()["error"]
    still_serving(server)


@pytest.mark.parametrize(("content", "name", "said"), [
    (png_header(100_000, 100_000), "bomb.png", "10000000000 pixels"),
    (png_header(15_000, 9_000), "wide.png", "is 15000 x 9000 px"),
    (png_header(10, 10), "tiny.png", "is 10 x 10 px"),
    (fits_header_only(100_000, 100_000), "huge.fits", "is 100000 x 100000 px"),
])
def test_422_for_absurd_dimensions_read_from_the_header(server, content, name, said):
    assert len(content) < 10_000  # the refusal comes from the header: nothing near that size was sent
    response = post_file(server, content, name)
    assert response.status_code == 422 and response.json()["field"] == "file"
    assert said in response.json()["error"]
    still_serving(server)


@pytest.mark.parametrize(("options", "field"), [
    ("{not json", "options"),
    ([1, 2], "options"),
    ({"colour": "red"}, "options.colour"),
    ({"fov_deg": 500}, "options.fov_deg"),
    ({"fov_deg": "ten"}, "options.fov_deg"),
    ({"fov_range_deg": [30, 10]}, "options.fov_range_deg"),
    ({"fov_deg": 10, "camera": "aptina-mt9p031"}, "options.camera"),
    ({"camera": "no-such-camera"}, "options.camera"),
    ({"camera": "../../etc/passwd"}, "options.camera"),
    ({"epoch": 12}, "options.epoch"),
    ({"time": "yesterday"}, "options.time"),
    ({"site": "atlantis"}, "options.site"),
    ({"latitude_deg": 40}, "options.longitude_deg"),
    ({"latitude_deg": 95, "longitude_deg": 0}, "options.latitude_deg"),
    ({"lens_correction": "yes"}, "options.lens_correction"),
    ({"guided": 1}, "options.guided"),
    ({"method": "guess"}, "options.method"),
    ({"method": "pyramid"}, "options.method"),
    ({"detection_preset": "magic"}, "options.detection_preset"),
    ({"detection": {"sigma": -1}}, "options.detection.sigma"),
    ({"detection": {"dark_frame": [1]}}, "options.detection.dark_frame"),
    ({"time_limit_s": 0}, "options.time_limit_s"),
])
def test_422_names_the_option(server, real_images, options, field):
    text = options if isinstance(options, str) else json.dumps(options)
    with open(real_images["roof.jpg"], "rb") as fh:
        response = server.client.post("/api/jobs", files={"file": ("roof.jpg", fh)}, data={"options": text})
    assert response.status_code == 422, response.text
    assert response.json()["field"] == field and response.json()["error"].startswith(field)
    still_serving(server)


@pytest.mark.parametrize(("scene", "field"), [({"fov_deg": 500}, "simulate.fov_deg"),
                                              ({"width": 10.5}, "simulate.width"), ({"ra_deg": 10}, "simulate.dec_deg"),
                                              ({"planet": "mars"}, "simulate.planet")])
def test_422_names_the_scene_parameter(server, scene, field):
    response = server.client.post("/api/jobs", files={"simulate": (None, json.dumps(scene))})
    assert response.status_code == 422 and response.json()["field"] == field
    still_serving(server)


def test_400_for_no_file_or_two(server, real_images):
    assert server.client.post("/api/jobs", files={"options": (None, "{}")}).status_code == 400
    content = real_images["roof.jpg"].read_bytes()
    response = server.client.post("/api/jobs", files=[("file", ("a.jpg", content)), ("file", ("b.jpg", content))])
    assert response.status_code == 400 and "POST /api/batches" in response.json()["error"]
    still_serving(server)


@pytest.mark.parametrize("path", [
    "/api/jobs/..%2F..%2Fetc%2Fpasswd", "/api/jobs/%2E%2E", "/api/jobs/ABCDEF", "/api/jobs/" + "0" * 32,
    "/api/jobs/" + "0" * 31 + "g", "/api/batches/..%2Fjobs", "/api/batches/" + "f" * 32, "/jobs/" + "1" * 32,
])
def test_404_for_malformed_or_unknown_ids(server, path):
    response = server.client.get(path)
    assert response.status_code == 404
    still_serving(server)


def test_404_for_file_names_outside_the_job(server, real_images):
    job_id = server.submit(real_images["crappy.jpg"]).json()["id"]
    server.wait_job(job_id)
    for name in ("..%2Fjob.json", "job.json", "state.json", "input.jpg", "record.npz", "%2Fetc%2Fpasswd",
                 "..%2F..%2F..%2Fetc%2Fpasswd", "nothing.png"):
        response = server.client.get(f"/api/jobs/{job_id}/files/{name}")
        assert response.status_code == 404, name
        assert "error" in response.json()
    assert server.client.get(f"/api/jobs/{job_id}/files/annotated.png").status_code == 200
    still_serving(server)


def test_range_requests_on_a_result_file(server, real_images):
    """Before: Starlette answered another unit or a backwards range with a plain-text 400, and a
    set with one range past the end with an empty 416; now they are ignored, served in part or
    refused in JSON."""
    job_id = server.submit(real_images["crappy.jpg"]).json()["id"]
    server.wait_job(job_id)
    url = f"/api/jobs/{job_id}/files/detections.csv"
    whole = server.client.get(url).content
    size = len(whole)
    for value in ("items=0-5", "bytes=5-2", "bytes=abc"):
        response = server.client.get(url, headers={"Range": value})
        assert response.status_code == 200 and response.content == whole, value
    part = server.client.get(url, headers={"Range": f"bytes=0-9,{size + 10}-"})
    assert part.status_code == 206 and part.content == whole[:10]
    assert part.headers["content-range"] == f"bytes 0-9/{size}"
    refused = server.client.get(url, headers={"Range": f"bytes={size}-"})
    assert refused.status_code == 416 and refused.headers["content-range"] == f"bytes */{size}"
    assert refused.json()["field"] == "Range" and f"{size} bytes long" in refused.json()["error"]
    still_serving(server)


def test_403_for_a_cross_site_post(server, real_images):
    with open(real_images["roof.jpg"], "rb") as fh:
        response = server.client.post("/api/jobs", files={"file": ("roof.jpg", fh)},
                                      headers={"Origin": "http://evil.example"})
    assert response.status_code == 403
    assert server.client.delete("/api/jobs/" + "0" * 32, headers={"Origin": "null"}).status_code == 403
    still_serving(server)


def test_nothing_is_run_through_a_shell():
    sources = [*sorted((SOURCES / "web").rglob("*.py")), SOURCES / "cli" / "_web_cmd.py"]
    assert len(sources) > 10
    pattern = re.compile(r"\bsubprocess\b|os\.system|os\.popen|shell\s*=\s*True|\bpty\b|os\.exec")
    offenders = [f"{p.name}: {m.group(0)}" for p in sources for m in pattern.finditer(p.read_text())]
    assert offenders == []


def test_the_jobs_folder_holds_only_server_made_names(server):
    jobs = server.data_dir / "jobs"
    names = [p.name for p in jobs.iterdir()]
    assert names and all(re.fullmatch(r"[0-9a-f]{32}", n) for n in names)
    inputs = {q.name for p in jobs.iterdir() for q in p.iterdir() if q.name.startswith("input")}
    assert inputs <= {"input.jpg", "input.png", "input.fits", "input.tif"}


BIG = "9" * 400
"""A whole number far past the float range (json.loads reads it as an int of 400 digits)."""


@pytest.mark.parametrize(("text", "field"), [
    ('{"fov_deg": ' + BIG + "}", "options.fov_deg"),
    ('{"fov_range_deg": [5, ' + BIG + "]}", "options.fov_range_deg"),
    ('{"epoch": ' + BIG + "}", "options.epoch"),
    ('{"time_limit_s": -' + BIG + "}", "options.time_limit_s"),
])
def test_422_for_a_whole_number_past_the_float_range(server, real_images, text, field):
    """Before: 500 (OverflowError where the check compared the int with a float)."""
    with open(real_images["roof.jpg"], "rb") as fh:
        response = server.client.post("/api/jobs", files={"file": ("roof.jpg", fh)}, data={"options": text})
    assert response.status_code == 422, response.text
    assert response.json()["field"] == field
    still_serving(server)


@pytest.mark.parametrize(("scene", "field"), [('{"width": ' + BIG + "}", "simulate.width"),
                                              ('{"seed": ' + BIG + "}", "simulate.seed"),
                                              ('{"sensor": ["generic-cmos"]}', "simulate.sensor"),
                                              ('{"sensor": {}}', "simulate.sensor")])
def test_422_for_a_scene_parameter_of_the_wrong_kind(server, scene, field):
    """Before: 500 (OverflowError; 'unhashable type' for a list or object as the sensor)."""
    response = server.client.post("/api/jobs", files={"simulate": (None, scene)})
    assert response.status_code == 422, response.text
    assert response.json()["field"] == field
    still_serving(server)


@pytest.mark.parametrize("text", ['{"fov_deg": NaN}', '{"fov_deg": Infinity}', "[" * 8000 + "]" * 8000])
def test_json_that_is_not_json_is_refused(server, real_images, text):
    """NaN and Infinity are not JSON; 8000 nested lists (under the options field's 16 KB) ended
    in a RecursionError and a 500."""
    with open(real_images["roof.jpg"], "rb") as fh:
        response = server.client.post("/api/jobs", files={"file": ("roof.jpg", fh)}, data={"options": text})
    assert response.status_code == 422, response.text
    assert response.json()["field"] == "options"
    still_serving(server)


def test_400_for_a_body_nested_too_deeply(server):
    """30,000 nested lists as a JSON body ended in a RecursionError and a 500."""
    nested = server.client.post("/api/cameras", content=("[" * 30000 + "]" * 30000).encode(),
                                headers={"Content-Type": "application/json"})
    assert nested.status_code == 400 and "nested too deeply" in nested.json()["error"]
    still_serving(server)


@pytest.mark.parametrize(("body", "field"), [
    ({"analysis": "histograms", "sets": [{"name": 5, "jobs": ["0" * 32]}]}, "sets[0].name"),
    ({"analysis": "histograms", "sets": [{"jobs": ["0" * 32]}], "params": 5}, "params"),
    ({"analysis": "histograms", "sets": [{"jobs": ["0" * 32]}], "params": [1]}, "params"),
])
def test_422_for_analysis_requests_of_the_wrong_shape(server, body, field):
    """Before: 500 (a number as a set's name, params that are not an object)."""
    response = server.client.post("/api/analyses", json=body)
    assert response.status_code == 422, response.text
    assert response.json()["field"] == field
    still_serving(server)


def test_media_types_match_in_any_case(server, real_images):
    """Multipart/Form-Data and Application/JSON are the same media types (RFC 9110); before, 415."""
    profile = {"name": "case-cam", "width": 507, "height": 507, "fx": 1000.0}
    response = server.client.post("/api/cameras", content=json.dumps(profile).encode(),
                                  headers={"Content-Type": "Application/JSON"})
    assert response.status_code == 201, response.text
    boundary = "B0UND"
    body = (f"--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"roof.jpg\"\r\n\r\n").encode() \
        + real_images["roof.jpg"].read_bytes() + f"\r\n--{boundary}--\r\n".encode()
    response = server.client.post("/api/jobs", content=body,
                                   headers={"Content-Type": f"Multipart/Form-Data; boundary={boundary}"})
    assert response.status_code == 201, response.text
    still_serving(server)


def test_the_simulate_page_refuses_a_huge_whole_number(server):
    """Before: 500 (the form's sim_width of 400 digits overflowed in the scene's checks)."""
    response = server.client.post("/simulate", files={"sim_width": (None, BIG)})
    assert response.status_code == 422 and "options.sim_width" in response.text
    assert "at most 19 digits" in response.text
    still_serving(server)


def test_400_for_an_unknown_job_state_in_the_listing(server):
    """Before: 200 with an empty list, as if no job were in that state."""
    response = server.client.get("/api/jobs", params={"state": "bogus"})
    assert response.status_code == 400 and response.json()["field"] == "state"
    assert "queued, running, done, failed, cancelled" in response.json()["error"]
    assert server.client.get("/api/jobs", params={"state": "done"}).status_code == 200
    twice = server.client.get("/api/jobs?state=done&state=failed")  # before: the last one, silently
    assert twice.status_code == 400 and twice.json()["field"] == "state" and "2 times" in twice.json()["error"]
    still_serving(server)


def test_415_at_upload_for_a_fits_bitpix_the_reader_refuses(server):
    """Before: BITPIX = 17 was taken (201) and the job failed in the worker."""
    header = fits.Header([("SIMPLE", True), ("BITPIX", 16), ("NAXIS", 2), ("NAXIS1", 64), ("NAXIS2", 64)])
    content = header.tostring().encode("ascii").replace(b"BITPIX  =                   16",
                                                        b"BITPIX  =                   17")
    response = post_file(server, content + b"\x00" * 2880 * 3, "odd.fits")
    assert response.status_code == 415 and "BITPIX = 17" in response.json()["error"]
    still_serving(server)


def test_messages_name_the_upload_not_the_servers_folders(server):
    """Before: '... cannot identify image file '<data dir>/jobs/<id>/input.jpg'' at upload, and a
    damaged PNG's job error began with the job folder's absolute path."""
    response = post_file(server, b"\xff\xd8\xff", "three.jpg")
    assert response.status_code == 415
    assert str(server.data_dir) not in response.json()["error"] and "three.jpg" in response.json()["error"]
    cut = png_header(64, 64)  # its IDAT holds one row's worth of the 64 its IHDR declares
    job = post_file(server, cut, "cut.png").json()
    state = server.wait_job(job["id"])
    assert state["state"] == "failed" and "truncated or corrupt" in state["error"]
    assert str(server.data_dir) not in state["error"] and state["error"].startswith("input.png: ")
    still_serving(server)


@pytest.mark.parametrize(("analysis", "params", "said"), [
    ("gallery", {"stamp_px": 6}, "must be odd"),
    ("sweep", {"setting": "kernel"}, "3.0 is not a value of kernel"),
    ("corrections", {"camera": "nope"}, "unknown camera preset 'nope'"),
])
def test_422_for_analysis_params_only_the_analysis_refuses(server, analysis, params, said):
    """Before: 201, and the job failed in the worker (an even stamp, the sweep's default numbers
    for a text setting, an unknown camera)."""
    body = {"analysis": analysis, "sets": [{"jobs": ["0" * 32]}], "params": params}
    response = server.client.post("/api/analyses", json=body)
    assert response.status_code == 422, response.text
    assert response.json()["field"] == "params" and said in response.json()["error"]
    still_serving(server)
