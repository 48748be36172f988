"""Variable-star and bright-body flags."""

import numpy as np
from astropy.time import Time

from startrack.calibrate._apparent import rotation_tod_from_icrs
from startrack.calibrate._bodies import body_directions, bright_bodies_near, variable_flags
from startrack.frames import angle_between, rotation_from_radec_roll, vector_to_radec
from startrack.units import DEG


def test_variable_flags_know_mira_and_betelgeuse_but_not_a_constant_star():
    # Mira (omicron Ceti) HIP 10826, Betelgeuse HIP 27989, delta Cep HIP 110991; Sirius HIP 32349 is not flagged
    np.testing.assert_array_equal(variable_flags([10826, 27989, 110991, 32349, 999999999]),
                                  [True, True, True, False, False])


def test_camera_pointing_at_the_sun_is_flagged_and_the_sun_is_where_it_should_be():
    t = Time("2024-03-20T03:06:00", scale="utc")  # March equinox: the Sun near RA 0, Dec 0
    sun = body_directions(t, ("sun",))["sun"]
    ra_tod, dec_tod = vector_to_radec(rotation_tod_from_icrs(t).apply(sun))  # the equinox of date
    assert abs(float(dec_tod)) < 0.01 * DEG and min(float(ra_tod), 2 * np.pi - float(ra_tod)) < 0.03 * DEG
    ra, dec = vector_to_radec(sun)
    rot = rotation_from_radec_roll(float(ra) + 10 * DEG, float(dec), 0.0)
    flags = {f.name: f for f in bright_bodies_near(rot, t)}
    assert flags["sun"].near and 9.5 < flags["sun"].separation_deg < 10.5
    far = rotation_from_radec_roll(float(ra) + np.pi, -float(dec), 0.0)
    assert not next(f for f in bright_bodies_near(far, t) if f.name == "sun").near
    moon = body_directions(t, ("moon",))["moon"]
    assert angle_between(moon, sun) > 30 * DEG  # five days before full moon
