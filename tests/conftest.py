"""Shared fixtures: bodies (default TIP, Winter 3- and 2-segment, bent TALOS) and seeding;
the rule that a ``slow`` mark says what makes its test slow."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from posture_id.bodies.anthropometry import straight_links, winter_segments
from posture_id.bodies.body import load_body
from posture_id.bodies.urdf_writer import write_chain_urdf
from posture_id.dec.parameters import default_parameters

#: The project's shipped URDFs (``make bodies``).
URDF_DIR = Path(__file__).resolve().parents[1] / "urdf"


def pytest_collection_modifyitems(config, items):
    """A ``slow`` mark carries one argument, what makes the test slow, in a few words:
    ``@pytest.mark.slow("trains a network")``; a test marked without it is refused."""
    for item in items:
        for mark in item.iter_markers("slow"):
            reason = mark.args[0] if len(mark.args) == 1 else None
            if mark.kwargs or not isinstance(reason, str) or not reason.strip():
                raise pytest.UsageError(
                    f"{item.nodeid}: a slow mark says what makes the test slow, "
                    f'e.g. @pytest.mark.slow("trains a network")')


@pytest.fixture(autouse=True)
def _seed():
    np.random.seed(0)  # noqa: NPY002 - for any code that still uses the global RNG


@pytest.fixture(scope="session")
def tip():
    return load_body()


@pytest.fixture(scope="session")
def winter(tmp_path_factory):
    path = tmp_path_factory.mktemp("bodies") / "winter3.urdf"
    write_chain_urdf(path, "winter3", straight_links(winter_segments(1.80, 80.0, 3)))
    return load_body(path)


@pytest.fixture(scope="session")
def winter2(tmp_path_factory):
    path = tmp_path_factory.mktemp("bodies") / "winter2.urdf"
    write_chain_urdf(path, "winter2", straight_links(winter_segments(1.80, 80.0, 2)))
    return load_body(path)


@pytest.fixture(scope="session")
def winter1(tmp_path_factory):
    path = tmp_path_factory.mktemp("bodies") / "winter1.urdf"
    write_chain_urdf(path, "winter1", straight_links(winter_segments(1.80, 80.0, 1)))
    return load_body(path)


@pytest.fixture(scope="session")
def talos_bent():
    """TALOS lumped into three segments (urdf/talos_tip.urdf, made by ``make bodies``): a
    bent reference posture, its COM-above lines leaning up to 14° at θ = 0."""
    return load_body(URDF_DIR / "talos_tip.urdf")


@pytest.fixture(params=["tip", "winter", "winter2"])
def any_body(request):
    """The default TIP, a Winter 3-segment and a Winter 2-segment body."""
    return request.getfixturevalue(request.param)


def random_parameters(body, rng, spread=0.3):
    """Parameters around the body's defaults (classes random), as DecParameters."""
    from posture_id.dec.parameters import DecParameters, ModuleParameters

    defaults = default_parameters(body)
    mods = {}
    for joint, d in defaults.modules.items():
        f = np.abs(1.0 + spread * rng.standard_normal(4))
        mods[joint] = ModuleParameters(
            kp=d.kp * f[0], ki=d.ki * f[1], kd=d.kd * f[2], delay_s=d.delay_s * f[3],
            controls=str(rng.choice(["com", "joint"])), kpas=d.kpas, bpas=d.bpas,
        )
    return DecParameters(mods)
