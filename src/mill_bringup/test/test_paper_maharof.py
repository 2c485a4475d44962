"""Maharof 2018 on the offline simulator (equal to the distributed run:
test/test_lockstep_equality.py): our figures, which docs/papers.md quotes, and the paper's.

Tolerances. Our figures are pinned to rel 1e-3: the runs are deterministic offline
simulations of stable loops, so they move only by rounding (operation order, libm), far
below 1e-6; 1e-3 is the four significant digits the docs quote. A Q-filter cutoff 10 %
off moves the IMBDO 26 Hz figure by 8 %, a DFO frequency 1 % off the DFO figures by far
more than 1e-3. The comparisons with the paper are separate and say what they rest on.
"""

from __future__ import annotations

import functools

import pytest
from mill_analysis.papers import MAHAROF_TABLES, maharof, maharof_metrics
from mill_bringup.jobs.base import simulate
from mill_bringup.jobs.registry import job_for

from mill_bringup import scenario

PINNED = 1e-3  # numerics: see the module docstring

# docs/papers.md, "Maharof": RMSE [mm], MTE [mm], error amplitude at 26/52/78 Hz [µm]
OURS = {
    'pi': (0.1017, 0.1469, 3.150, 0.4581, 0.3879),
    'pi_imbdo': (0.1017, 0.1461, 1.644, 0.3871, 0.4691),
    'pi_dfo': (0.1016, 0.1438, 0.02438, 0.005893, 0.005813),
    'pi_imbdo_dfo': (0.1017, 0.1438, 0.01332, 0.005369, 0.006307),
}


@functools.cache
def record(variant: str):
    return simulate(job_for(scenario.load('maharof').variant(variant)))


def metrics(variant: str) -> tuple[float, ...]:
    rmse, mte, amps = maharof_metrics(record(variant))
    return (rmse, mte, *amps)


@pytest.mark.parametrize('variant', sorted(OURS))
def test_our_figures_are_the_ones_the_docs_quote(variant: str) -> None:
    assert metrics(variant) == pytest.approx(OURS[variant], rel=PINNED)


def test_plain_cascade_agrees_with_table_1() -> None:
    # The paper: RMSE 0.1016 mm, MTE 0.1477 mm. Both are the lag error ẋ_ref/k_v of the
    # 10 mm, 0.5 Hz sine, independent of the synthesised force; ours differ from the
    # machine's by 0.1 % and 0.5 % (its real drive against our identified model). The
    # force amplitudes were calibrated on the 26/52/78 Hz peaks (docs/papers.md); they come
    # out 0.3 / 1.6 / 4.5 % off.
    rmse, mte, *amps = metrics('pi')
    paper_rmse, paper_mte, paper_amps = MAHAROF_TABLES['pi']
    assert rmse == pytest.approx(paper_rmse, rel=2e-3)
    assert mte == pytest.approx(paper_mte, rel=1e-2)
    assert amps == pytest.approx(paper_amps, rel=5e-2)


def test_the_report_gives_the_papers_claims_their_verdicts() -> None:
    text = maharof({v: record(v) for v in OURS})
    # Every harmonic peak falls with IMBDO + DFO, as in the paper (−78.8/−34.8/−35.0 %) but
    # by 99 %: our plant is exactly the DFO's model apart from the dead time.
    assert (
        'reduces every harmonic peak (paper: −78.8/−34.8/−35.0 %)" (DFO zeta_h 0.05 (ours)): '
        '-99.6 % / -98.8 % / -98.4 % — agrees'
    ) in text
    # The RMSE is the sine's lag error, which no observer changes: the claim that IMBDO +
    # DFO gives the lowest RMSE does not hold (0.1017 mm against the DFO's 0.1016).
    assert 'claim "IMBDO + DFO gives the lowest RMSE and MTE" (DFO zeta_h 0.05 (ours)): ' in text
    assert 'MTE 0.1438 mm — DISAGREES' in text


def test_the_harmonic_verdict_depends_on_the_dfo_gains_we_chose() -> None:
    """The paper prints no DFO gains: with ζ_h = 0.1 instead of our 0.05 the IMBDO + DFO loop
    degrades and the 52 and 78 Hz peaks rise above the plain cascade's."""
    names = ('pi', 'pi_imbdo', 'pi_dfo', 'pi_imbdo_dfo', 'pi_imbdo_dfo_zeta_h0.1')
    text = maharof({v: record(v) for v in names})
    assert text.endswith(
        'over the readings (sample period 0.1 ms): lowest RMSE and MTE DISAGREES; every '
        "harmonic peak reduced depends on the DFO's ζ_h"
    )
    # The paper's DFO reduces each peak of the plain cascade; ours too.
    plain, dfo = metrics('pi')[2:], metrics('pi_dfo')[2:]
    assert all(d < p for d, p in zip(dfo, plain, strict=True))
