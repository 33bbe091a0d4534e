import pytest

from formation_env.aircraft.trim import trim


@pytest.fixture(scope="session")
def trim_a5():
    """The thesis's Table A.5 trim: 25 m/s, 1000 m, 2 kg fuel."""
    return trim(25.0, 1000.0, 2.0)
