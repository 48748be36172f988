import pytest
from slew_frames import simulate_slew


@pytest.fixture(scope="session")
def slew_frames():
    """The frames of :func:`slew_frames.simulate_slew` (rendered once for the tracker and CLI tests)."""
    return simulate_slew()
