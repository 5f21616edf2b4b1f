"""Would the recording be explained far better if it were not what the user says it is?

Two mistakes leave a recording that some model explains, only not the one asked for:

- **segment columns exchanged** (the lab's export mixed up two segments): the same
  network, on the same body, reads the recording with two neighbouring columns put back
  the other way round;
- **another person's body** (the URDF of someone else, or a template of the wrong size):
  the network reads it with the body made larger or smaller (every length ×b, masses kept:
  :func:`~posture_id.bodies.scaling.scaled_body`, factors :data:`SIZES`). A body's mass
  cannot be seen in sway at all (the gains scale with it); its size can, through its time
  scale √(J/m·g·h) ∝ √b, wherever inertia shapes the response. Another person's body is
  one far from the subject's: a fifth or more (a time scale a tenth or more off); a body
  a tenth off changes the time scale by 5 %, which the network's own error on clean sway
  matches (docs/identify.md, "Mistakes": a right body read best a tenth shorter), so
  only the far sizes are read.

Each alternative is judged as the answer is: the identified model re-simulated, its
stimulus-locked residual in units of the recording's own noise
(:func:`~posture_id.identify.noise_check.noise_check`). An alternative counts as evidence
only when the answer leaves more than the noise allows (and stays up: against a model that
falls, any reading that does not would win) and the alternative leaves at most
1/:data:`SWAP_GAIN` (columns) or 1/:data:`SIZE_GAIN` (size) of it (how often a right
recording is named: docs/identify.md, "Mistakes"); on people-like sway, whose noise hides
both, they are rarely called. On a recording whose noise is below :data:`MIN_NOISE_SHARE`
of its locked sway no other size is read: the network's own error is larger than such
noise. The identifier confirms a size named here before it reports it
(``Identifier._fits_within_noise``): when least squares on the given body explains the
recording within its noise, the size reading was the network's own error, and nothing
is named.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

from posture_id.bodies.body import Body
from posture_id.bodies.scaling import scaled_body
from posture_id.errors import PostureIdError
from posture_id.identify.mistakes import Check, Mistake
from posture_id.identify.noise_check import NOISE_RATIO_LIMIT
from posture_id.trials import PreparedTrial

__all__ = ["better_explanations", "columns_exchanged", "SIZES", "SWAP_GAIN", "SIZE_GAIN",
           "MIN_NOISE_SHARE"]

#: Body sizes tried, as factors on every length: another person's body, a fifth or more
#: smaller or larger (module docstring).
SIZES = (0.8, 1.25)
#: Exchanged columns are named when putting them back divides the residual by this.
SWAP_GAIN = 3.0
#: Another body size is named when it divides the residual by this.
SIZE_GAIN = 1.3

#: The least noise, as a share of the recorded locked sway, at which other body sizes are
#: read: the network's own error on right clean recordings is 0.5–16 % of the locked body
#: sway (benchmarks/columns_on_clean.py), so on a cleaner recording (a robot's sensors, a
#: simulation without noise) it reads as tens of noise units and two sizes' readings
#: differ by chance (tests/test_alternative_readings.py:
#: a noise-free 2-segment Winter recording at 3° read with a body 20 % shorter). Columns
#: put back are read on any recording: on right ones, noise-free or not, the best reading
#: of two columns exchanged divided the residual by at most 1.5, never the 3 of
#: :data:`SWAP_GAIN` (48 recordings: the TIP and 2- and 3-segment Winter bodies, four
#: PRTSs, two draws each, no noise or 0.005°; benchmarks/columns_on_clean.py).
MIN_NOISE_SHARE = 0.003

#: (trial, body) → the network's answer's residual in units of the noise (inf: it falls).
RatioOf = Callable[[PreparedTrial, Body], float]


def better_explanations(trial: PreparedTrial, body: Body, ratio: float, relative: float,
                        ratio_of: RatioOf, sizes: bool = True) -> tuple[Mistake, ...]:
    """The mistakes an alternative reading reveals (module docstring).

    Args:
        trial, body: as identified. ratio: the answer's residual in units of the noise,
            by the same reading as ``ratio_of`` gives the alternatives'. relative: the
            answer's residual as a share of the recorded locked sway (``relative / ratio``
            is the noise's share, against :data:`MIN_NOISE_SHARE`).
        ratio_of: the network's reading of a trial on a body, judged.
        sizes: try other body sizes (a network trained on one body cannot).
    """
    if not (NOISE_RATIO_LIMIT < ratio < math.inf):  # a model that falls is no yardstick
        return ()
    # on a recording cleaner than the network's own error, sizes read by chance; columns
    # put back do not (they need a third of the residual: module docstring)
    sizes = sizes and relative / ratio >= MIN_NOISE_SHARE
    found = []
    names = trial.recording.segments
    best = None
    for k in range(len(names) - 1):
        other = ratio_of(columns_exchanged(trial, k), body)
        if other * SWAP_GAIN <= ratio and (best is None or other < best[1]):
            best = (k, other)
    if best is not None:
        k, other = best
        found.append(Mistake(Check.COLUMNS_EXCHANGED, ratio / other, SWAP_GAIN, (
            f"the {names[k]} and {names[k + 1]} columns read the other way round leave "
            f"{other:.2f}× the noise against {_times(ratio)} as given: are they exchanged?")))
    if sizes:
        try:
            bodies = [(factor, scaled_body(body, factor)) for factor in SIZES]
        except PostureIdError:  # a body this check cannot copy: no evidence either way
            return tuple(found)
        tried = [(factor, ratio_of(trial, scaled)) for factor, scaled in bodies]
        factor, other = min(tried, key=lambda t: t[1])
        if other * SIZE_GAIN <= ratio:
            found.append(Mistake(Check.ANOTHER_BODY, ratio / other, SIZE_GAIN, (
                f"a body {abs(100 * (factor - 1)):.0f} % {'taller' if factor > 1 else 'shorter'}"
                f" than {body.name}'s explains the sway better ({other:.2f}× the noise against "
                f"{_times(ratio)}): is the URDF this subject's? (the sway shows a body's "
                "size, not its mass)")))
    return tuple(found)


def columns_exchanged(trial: PreparedTrial, k: int) -> PreparedTrial:
    """``trial`` with its segment columns k and k + 1 the other way round."""
    theta = trial.recording.theta.copy()
    theta[:, [k, k + 1]] = theta[:, [k + 1, k]]
    return replace(trial, recording=replace(trial.recording, theta=theta))


def _times(ratio: float) -> str:
    return "a fall" if not math.isfinite(ratio) else f"{ratio:.2f}×"
