"""Every plan keeps a margin from each joint's hard limit (issue 39: the Panda's export rode its
joint-5 hard limit). The robot carries both: its URDF's hard limits, which an exported URDF
keeps, and the usable ones the IK, the learners and the export's checks keep to."""

from __future__ import annotations

import numpy as np
import pytest

from studio.export import check_trajectory
from studio.kinematics import LIMIT_MARGIN_RAD, KinematicsError, load_robot


def test_a_robot_plans_within_its_hard_limits_less_the_margin():
    panda = load_robot("panda")
    assert LIMIT_MARGIN_RAD >= 0.02
    np.testing.assert_allclose(panda.lower, panda.hard_lower + LIMIT_MARGIN_RAD)
    np.testing.assert_allclose(panda.upper, panda.hard_upper - LIMIT_MARGIN_RAD)
    assert 'upper="2.8973"' in panda.urdf_text  # the exported URDF keeps the hard limits
    assert np.all(panda.home >= panda.lower) and np.all(panda.home <= panda.upper)
    target = panda.forward(np.where(panda.hard_upper < 3.0, panda.hard_upper, 0.5))
    q = panda.inverse(target, iterations=200).q
    assert np.all(q >= panda.lower - 1e-12) and np.all(q <= panda.upper + 1e-12)


def test_the_checks_refuse_a_joint_within_the_margin_and_another_margin_can_be_asked():
    panda = load_robot("panda")
    q = np.tile(panda.home, (3, 1))
    q[:, 4] = panda.hard_upper[4] - 0.5 * LIMIT_MARGIN_RAD  # inside the hard limit, not the margin
    times = np.array([0.0, 1.0, 2.0])
    [finding] = [f for f in check_trajectory(panda, times, q) if f.what == "position"]
    assert "panda_joint5" in finding.sentence and "margin" in finding.sentence
    assert not [
        f for f in check_trajectory(panda.with_limit_margin(0.0), times, q) if f.what == "position"
    ]
    wide = panda.with_limit_margin(0.1)
    np.testing.assert_allclose(wide.upper, panda.hard_upper - 0.1)
    assert panda.upper[0] == pytest.approx(panda.hard_upper[0] - LIMIT_MARGIN_RAD)  # unchanged
    with pytest.raises(KinematicsError, match="limit margin"):
        panda.with_limit_margin(-0.1)
