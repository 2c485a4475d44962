"""The tuning rule of the ADRC loop for a sample rate and a delay. ROS-free.

A loop sampled every T with N samples between a measurement and the period its command
acts in loses phase in proportion to (N + ½)·T·ω at a crossover ω (the delay and the
hold's half sample), and a sample more than designed for adds T·ω. An extended-state
observer whose bandwidth ω_o keeps ω_o·(N + 3/2)·T at a fixed fraction therefore keeps its
margins at every rate, and the controller's bandwidth sits a fixed ratio below the
observer's:

    ω_o = K_O / ((N + 3/2)·T),   ω_c = ω_o / R_C

with K_O = 0.75 and R_C = 3. For the ESO of degree 0 (mill_observers.eso) and the ADRC law
(mill_controllers.pd_law) on x'' = b·u + ξ, this gives (checked by simulation at 100 Hz to
1 kHz with N = 0, 1 in mill_bringup's test_loop_tuning): a stable loop for a true input
gain from 0.6 to 1.6 times the nominal one, and with one more sample of delay than
designed for. The papers' tunings are not this rule: Beltrán's 700 rad/s observer is a
1 kHz, no-delay design and loses its stability with a 20 % gain error or one more sample.
"""

from __future__ import annotations

from dataclasses import dataclass

K_O = 0.75  # ω_o·(N + 3/2)·T
R_C = 3.0  # ω_o / ω_c
GAIN_MARGIN = (0.6, 1.6)  # the true/nominal input gains the rule keeps stable
EXTRA_DELAY = 1  # samples more than designed for that the rule keeps stable


@dataclass(frozen=True)
class LoopTuning:
    sample_period: float  # T [s]
    delay: int  # N [samples]
    omega_o: float  # observer bandwidth [rad/s]
    omega_c: float  # controller bandwidth [rad/s]

    def describe(self) -> str:
        return (
            f'tuning rule at T = {1e3 * self.sample_period:g} ms, {self.delay} sample(s) of '
            f'delay: observer {self.omega_o:.1f} rad/s, controller {self.omega_c:.1f} rad/s '
            f'(stable for {GAIN_MARGIN[0]:g}-{GAIN_MARGIN[1]:g} x the input gain and '
            f'{EXTRA_DELAY} more sample of delay)'
        )


def loop_tuning(sample_period: float, delay: int) -> LoopTuning:
    """The rule's bandwidths for a sample period T [s] and a delay of N samples."""
    if not sample_period > 0.0 or delay < 0:
        raise ValueError(f'need T > 0 and N >= 0, got T = {sample_period!r}, N = {delay!r}')
    omega_o = K_O / ((delay + 1.5) * sample_period)
    return LoopTuning(sample_period, delay, omega_o, omega_o / R_C)
