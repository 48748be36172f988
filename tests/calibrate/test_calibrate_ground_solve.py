"""A photo from the ground, rendered from the apparent, refracted sky, solved back to where the
camera pointed in RA / Dec and altitude / azimuth."""

import numpy as np
from astropy.time import Time

from startrack import Camera, solve_image
from startrack.calibrate._apparent import apparent_vectors
from startrack.calibrate._ground import pointing_altaz, refract_icrs, rotation_enu_from_icrs
from startrack.calibrate._ground_solve import solve_ground_photo
from startrack.calibrate._sites import Site
from startrack.catalog import load_catalog
from startrack.frames import attitude_error, boresight, rotation_from_radec_roll, vector_to_radec
from startrack.simulate import get_sensor_preset, render_stars
from startrack.units import ARCMIN, ARCSEC, DEG

SITE = Site("logan", 41.74, -111.83, 1400.0)
TIME = Time("2012-10-05T04:00:00", scale="utc")
CAMERA = Camera.from_fov(1024, 768, 20.0)


def _photo(altitude_deg: float, azimuth_deg: float):
    alt, az = np.radians(altitude_deg), np.radians(azimuth_deg)
    axis_enu = np.array([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)])
    ra, dec = vector_to_radec(rotation_enu_from_icrs(TIME, SITE).inv().apply(axis_enu))
    truth = rotation_from_radec_roll(ra, dec, 0.4)
    catalog = load_catalog().brighter_than(7.0)
    seen = refract_icrs(apparent_vectors(catalog, TIME), TIME, SITE)  # what the atmosphere shows
    sim = render_stars(CAMERA, truth, seen, catalog.v_mag, catalog.hip, sensor=get_sensor_preset("generic-cmos"),
                       rng=3)
    return sim.image, truth


def test_ground_photo_is_solved_against_the_apparent_refracted_sky():
    image, truth = _photo(20.0, 135.0)
    ground = solve_ground_photo(image, SITE, time=TIME, fov_deg=20.0)
    assert ground.solution.solved
    pixel = CAMERA.pixel_scale_arcsec * ARCSEC
    assert attitude_error(truth, ground.solution.rot_cam_from_icrs) < 0.5 * pixel
    alt, az = pointing_altaz(truth, TIME, SITE)
    assert abs(ground.altitude_deg - alt) < 10 * ARCSEC / DEG and abs(ground.azimuth_deg - az) < 30 * ARCSEC / DEG
    # refraction at 20 deg altitude lifts stars by ~2.6 arcmin: ignoring it misplaces the boresight
    plain = solve_image(image, fov_deg=20.0, epoch=TIME)
    plain_error = np.arccos(np.clip(boresight(plain.rot_cam_from_icrs) @ boresight(truth), -1, 1))
    assert plain_error > 1.5 * ARCMIN
    assert alt > 20.0  # the reported altitude is the apparent one (refraction raises it)


def test_cli_solve_with_a_site_prints_altitude_and_azimuth(tmp_path, capsys):
    import json

    from startrack.cli import main
    from startrack.io import write_png

    image, truth = _photo(35.0, 250.0)
    path = tmp_path / "ground.png"
    write_png(path, image)
    code = main(["solve", str(path), "--fov-deg", "20", "--latitude-deg", str(SITE.latitude_deg),
                 "--longitude-deg", str(SITE.longitude_deg), "--height-m", "1400", "--time", TIME.isot, "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["status"] == "ok"
    alt, az = pointing_altaz(truth, TIME, SITE)
    assert abs(out["altitude_deg"] - alt) < 0.01 and abs(out["azimuth_deg"] - az) < 0.01
    assert main(["solve", str(path), "--latitude-deg", "41"]) == 2
