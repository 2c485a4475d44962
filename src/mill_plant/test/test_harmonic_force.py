"""HarmonicForce (Maharof 2018 eq. (5)): exact spectrum, time window, parameters."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mill_common.parameters import ParameterError, validate_all
from mill_models.axis_data import BELTRAN_TABLE1
from mill_plant.harmonic_force import SYNTHESISED_AMPLITUDES, HarmonicForce, HarmonicParams

ORIGIN = (0.0, 0.0, 0.0)


def _spectrum(force: HarmonicForce, axis: int, duration: float, rate: float) -> np.ndarray:
    n = round(duration * rate)
    f = np.array([force.force(k / rate, ORIGIN, ORIGIN)[axis] for k in range(n)])
    return np.fft.rfft(f) / n


def test_defaults_are_26_52_78_hz_like_the_dfo() -> None:
    force = HarmonicForce.from_parameters({})
    assert force.frequencies == pytest.approx((26.0, 52.0, 78.0), rel=1e-15)
    # mill_observers is not a dependency of mill_plant: compare only where it is installed.
    dfo_module = pytest.importorskip('mill_observers.dfo')
    dfo = {s.name: s.default for s in dfo_module.Dfo.PARAMETERS}
    assert force.spindle_speed == dfo['spindle_speed']
    assert force.teeth == dfo['teeth']
    assert list(force.harmonics) == dfo['harmonics']


def test_spectrum_has_exactly_the_configured_amplitudes_and_mean() -> None:
    amplitudes = [30.0, 12.5, 4.0]
    phases = [0.3, -1.1, 2.0]
    force = HarmonicForce.from_parameters(
        {'amplitudes': amplitudes, 'phases': phases, 'mean': 17.0, 'axis_weights': [1.0, -0.5, 0.0]}
    )
    rate = 2000.0  # 1 s = 26 whole periods of f_0: 1 Hz bins, 26/52/78 Hz on bins
    x = _spectrum(force, 0, 1.0, rate)
    assert x[0].real == pytest.approx(17.0, abs=1e-9)
    for freq, amp, ph in zip((26, 52, 78), amplitudes, phases, strict=True):
        # A sin(ωt + θ) = A cos(ωt + θ − π/2): single-sided bin 2X_k = A e^{j(θ − π/2)}
        assert 2.0 * abs(x[freq]) == pytest.approx(amp, abs=1e-9)
        assert np.angle(x[freq]) == pytest.approx(ph - 0.5 * math.pi, abs=1e-9)
    others = np.delete(np.abs(x), [0, 26, 52, 78])
    assert np.max(others) < 1e-9
    y = _spectrum(force, 1, 1.0, rate)
    assert y[0].real == pytest.approx(-8.5, abs=1e-9)
    assert 2.0 * abs(y[52]) == pytest.approx(6.25, abs=1e-9)
    assert np.max(np.abs(_spectrum(force, 2, 1.0, rate))) == 0.0


def test_default_spectrum() -> None:
    x = _spectrum(HarmonicForce.from_parameters({}), 0, 1.0, 2000.0)
    assert x[0].real == pytest.approx(45.0, abs=1e-9)
    for freq, amp in zip((26, 52, 78), (39.3, 7.3, 7.6), strict=True):
        assert 2.0 * abs(x[freq]) == pytest.approx(amp, abs=1e-9)


def test_default_amplitudes_follow_from_table_2() -> None:
    """Back-compute the disturbance from Maharof Table 2 through the eq. (1) closed loop."""
    a, b, c, td = 78020.0, 163.0, 193.3, 1.2e-3  # eq. (1): mm/(V s²), 1/s, 1/s², s
    k_v, k_p, k_i = 225.0, 0.00661, 0.12075  # §4.1
    m_e = BELTRAN_TABLE1['x'].effective_mass
    for freq, error_um, default in zip(
        (26.0, 52.0, 78.0),
        (3.158, 0.4511, 0.3711),
        SYNTHESISED_AMPLITUDES,
        strict=True,
    ):
        s = 2j * math.pi * freq
        g = a / (s * s + b * s + c) * np.exp(-s * td)
        y_per_volt = abs(g / (1.0 + g * (k_p + k_i / s) * (s + k_v)))  # mm/V
        volts = error_um * 1e-3 / y_per_volt
        newtons = volts * a * 1e-3 * m_e  # same acceleration of the suite's x carriage
        assert newtons == pytest.approx(default, abs=0.05)
    # The default mean keeps the default force one-signed.
    force = HarmonicForce.from_parameters({})
    samples = [force.profile(t) for t in np.linspace(0.0, 1.0 / 26.0, 5001)]
    assert min(samples) > 0.0


def test_zero_amplitude_is_exactly_the_mean() -> None:
    force = HarmonicForce.from_parameters({'amplitudes': [0.0, 0.0, 0.0], 'mean': 12.25})
    for t in np.linspace(0.0, 2.0, 1001):
        assert force.force(float(t), ORIGIN, ORIGIN) == (12.25, 0.0, 0.0)


def test_time_window() -> None:
    force = HarmonicForce(
        HarmonicParams(start_time=0.5, end_time=1.5, axis_weights=(0.0, 1.0, 2.0))
    )
    assert force.force(0.4999, ORIGIN, ORIGIN) == (0.0, 0.0, 0.0)
    assert force.force(1.5, ORIGIN, ORIGIN) == (0.0, 0.0, 0.0)
    f = force.force(0.5, ORIGIN, ORIGIN)
    # Phases refer to t = 0, not to start_time.
    expected = 45.0 + sum(
        a * math.sin(2 * math.pi * 26.0 * m * 0.5)
        for a, m in zip((39.3, 7.3, 7.6), (1, 2, 3), strict=True)
    )
    assert f[0] == 0.0
    assert f[1] == pytest.approx(expected, rel=1e-12)
    assert f[2] == 2.0 * f[1]


def test_tooth_passing_reading() -> None:
    values = {'spindle_speed': 1800.0, 'teeth': 2, 'harmonics': [1.0, 2.0], 'amplitudes': [5, 1]}
    force = HarmonicForce.from_parameters(values)
    assert force.frequencies == pytest.approx((60.0, 120.0))
    assert force.phases == (0.0, 0.0)  # missing phases: zero for each harmonic


@pytest.mark.parametrize(
    ('values', 'name'),
    [
        ({'spindle_speed': 0.0}, 'harmonic.spindle_speed'),
        ({'spindle_speed': math.nan}, 'harmonic.spindle_speed'),
        ({'teeth': 0}, 'harmonic.teeth'),
        ({'teeth': 1.5}, 'harmonic.teeth'),
        ({'harmonics': []}, 'harmonic.harmonics'),
        ({'harmonics': [1.0, 1.0, 2.0]}, 'harmonic.harmonics'),
        ({'harmonics': [1.0, -2.0, 3.0]}, 'harmonic.harmonics'),
        ({'amplitudes': [1.0, 2.0]}, 'harmonic.amplitudes'),
        ({'harmonics': [1.0, 2.0]}, 'harmonic.amplitudes'),
        ({'amplitudes': [1.0, -2.0, 3.0]}, 'harmonic.amplitudes'),
        ({'amplitudes': [1.0, math.inf, 3.0]}, 'harmonic.amplitudes'),
        ({'phases': [0.0]}, 'harmonic.phases'),
        ({'phases': [0.0, math.nan, 0.0]}, 'harmonic.phases'),
        ({'mean': math.inf}, 'harmonic.mean'),
        ({'mean': 'ten'}, 'harmonic.mean'),
        ({'axis_weights': [1.0, 0.0]}, 'harmonic.axis_weights'),
        ({'start_time': -1.0}, 'harmonic.start_time'),
        ({'start_time': 2.0, 'end_time': 1.0}, 'harmonic.end_time'),
        ({'end_time': 0.0}, 'harmonic.end_time'),
    ],
)
def test_bad_parameters_are_refused(values: dict, name: str) -> None:
    with pytest.raises(ParameterError) as info:
        HarmonicForce.from_parameters(values)
    assert info.value.name == name


def test_parameter_specs() -> None:
    assert all(spec.description for spec in HarmonicForce.PARAMETERS)
    assert all('.' not in spec.name for spec in HarmonicForce.PARAMETERS)
    defaults = validate_all(HarmonicForce.PARAMETERS, {})
    force = HarmonicForce.from_parameters(defaults)
    assert force.amplitudes == (39.3, 7.3, 7.6)
    assert force.mean == 45.0
    assert force.end_time == math.inf
