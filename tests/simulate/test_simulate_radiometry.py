"""Radiometry: the V-band zero point, magnitude scaling, settings validation, the FAR-MST preset."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.constants as const

from startrack import get_preset
from startrack.errors import InvalidInputError
from startrack.simulate import (
    HUFFMAN2006_EQ34_ZERO_POINT_PHOTONS_S_M2,
    V_MAG0_PHOTONS_S_M2,
    Detector,
    Optics,
    Sensor,
    electrons_from_magnitude,
    get_sensor_preset,
    magnitude_from_electrons,
)


def test_zero_point_agrees_with_the_f_lambda_form_of_the_v_band_zero_point():
    # Bessell, Castelli & Plez (1998): f_lambda(V=0) = 3.631e-9 erg s^-1 cm^-2 A^-1
    # = 3.631e-11 W m^-2 nm^-1; photons = f_lambda * bandwidth / (h c / lambda), 88 nm at 550 nm.
    f_lambda_w_m2_nm = 3.631e-11
    photon_energy_j = const.h * const.c / 550e-9
    reference = f_lambda_w_m2_nm * 88.0 / photon_energy_j
    assert V_MAG0_PHOTONS_S_M2 == pytest.approx(reference, rel=0.02)
    assert 8e9 < V_MAG0_PHOTONS_S_M2 < 1.1e10  # "about 1e10 photons s^-1 m^-2"


def test_unit_aperture_and_exposure_give_the_zero_point():
    e = electrons_from_magnitude(0.0, aperture_area_m2=1.0, exposure_s=1.0)
    assert float(e) == pytest.approx(V_MAG0_PHOTONS_S_M2, rel=1e-12)


def test_five_magnitudes_are_a_factor_100():
    e = electrons_from_magnitude([1.0, 6.0], aperture_area_m2=1e-4, exposure_s=0.1)
    assert e[0] / e[1] == pytest.approx(100.0, rel=1e-12)


@pytest.mark.parametrize("name", ["aperture_area_m2", "exposure_s", "transmission",
                                  "quantum_efficiency"])
def test_electrons_are_proportional_to_each_factor(name):
    base = {"aperture_area_m2": 2e-4, "exposure_s": 0.2, "transmission": 0.4,
            "quantum_efficiency": 0.3}
    doubled = dict(base, **{name: 2 * base[name]})
    ratio = electrons_from_magnitude(3.0, **doubled) / electrons_from_magnitude(3.0, **base)
    assert float(ratio) == pytest.approx(2.0, rel=1e-12)


def test_far_mst_preset_matches_seed_000_table_7_1():
    s = get_sensor_preset("FAR_MST")
    assert s.optics.aperture_area_m2 == pytest.approx(1.77e-4)
    assert s.detector.gain_e_per_adu == 10.0
    assert s.detector.read_noise_e == 39.0
    assert s.detector.dark_current_e_s == 410.0
    assert s.exposure_s == 0.1
    assert s.psf_sigma_px == 2.5
    assert s.detector.bit_depth == 10 and s.detector.max_adu == 1023
    # QE from the seed's FFSR 0.12 A/W at 550 nm: QE = R h c / (e lambda)
    qe = 0.12 * const.h * const.c / (const.e * 550e-9)
    assert s.detector.quantum_efficiency == pytest.approx(qe, rel=1e-6)
    assert s.dark_e == pytest.approx(41.0)
    assert get_preset("far-mst").width == 1280  # the camera preset it pairs with


def test_far_mst_magnitude_zero_signal_is_the_stated_number():
    # 8.78e9 photons/s/m^2 * 1.77e-4 m^2 * 0.2705 * 0.1 s = 4.20e4 e-
    assert float(get_sensor_preset("far-mst").electrons(0.0)) == pytest.approx(4.204e4, rel=1e-3)


def test_magnitude_round_trip(plain_sensor):
    mags = np.array([-1.0, 2.5, 7.25])
    electrons = plain_sensor.electrons(mags)
    assert magnitude_from_electrons(electrons, plain_sensor) == pytest.approx(mags)


def test_optics_from_diameter():
    optics = Optics.from_diameter(0.015)
    assert optics.aperture_area_m2 == pytest.approx(math.pi * 0.015**2 / 4)
    assert optics.aperture_diameter_m == pytest.approx(0.015)


def test_with_exposure_scales_signal_and_dark(plain_sensor):
    longer = plain_sensor.with_exposure(3.0)
    assert longer.electrons(4.0) == pytest.approx(3.0 * plain_sensor.electrons(4.0))
    assert longer.dark_e == pytest.approx(3.0 * plain_sensor.dark_e)


@pytest.mark.parametrize("make", [
    lambda: Optics(aperture_area_m2=-1.0),
    lambda: Optics(aperture_area_m2=1e-4, transmission=1.5),
    lambda: Optics(aperture_area_m2=1e-4, psf_sigma_px=0.0),
    lambda: Detector(bit_depth=17),
    lambda: Detector(bit_depth=12.0),
    lambda: Detector(read_noise_e=-1.0),
    lambda: Detector(gain_e_per_adu=float("nan")),
    lambda: Detector(quantum_efficiency=0.0),
    lambda: Sensor(optics=Optics(aperture_area_m2=1e-4), exposure_s=0.0),
    lambda: Sensor(optics="lens"),
    lambda: electrons_from_magnitude(np.nan, aperture_area_m2=1e-4, exposure_s=1.0),
    lambda: electrons_from_magnitude(1.0, aperture_area_m2="big", exposure_s=1.0),
    lambda: get_sensor_preset("hubble"),
])
def test_misuse_raises_invalid_input(make):
    with pytest.raises(InvalidInputError):
        make()


def test_seed_scale_preset_reproduces_seed_000_eq_3_4():
    # Huffman 2006: with Table 7.1 values eq. 3.4 gives eNum ~ 1.34e4 e- at M_V 6
    seed = get_sensor_preset("far-mst-seed-eq34")
    literal = 1.77e-4 * 0.12 * 0.1 * 10.0 * 10.0 ** ((28.0 - 6.0) / 2.5)  # a FFSR t g 10^(..)
    assert float(seed.electrons(6.0)) == pytest.approx(literal, rel=1e-4)
    assert float(seed.electrons(6.0)) == pytest.approx(1.34e4, rel=0.01)
    assert seed.detector == get_sensor_preset("far-mst").detector
    assert seed.optics.zero_point_photons_s_m2 == HUFFMAN2006_EQ34_ZERO_POINT_PHOTONS_S_M2
