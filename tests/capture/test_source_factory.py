"""One factory of sources for the command line and the page: the page's kinds (the camera and
the hand guide it feeds, the network bridge with its token) come from the same spec."""

from __future__ import annotations

import pytest

from studio.capture import (
    CameraSource,
    CaptureError,
    HandSource,
    NetworkSource,
    SimulatorSource,
    source_from_spec,
)


@pytest.mark.parametrize(
    ("spec", "kind", "side"), [("camera", CameraSource, "right"), ("hand:left", HandSource, "left")]
)
def test_the_page_gets_its_fed_sources_from_the_factory(spec, kind, side):
    source = source_from_spec(spec, fed=True)
    assert isinstance(source, kind) and source.side == side


def test_a_command_line_cannot_choose_a_source_only_the_page_feeds():
    with pytest.raises(CaptureError, match="fed by the studio's page"):
        source_from_spec("camera")


def test_a_bad_side_is_one_sentence():
    with pytest.raises(CaptureError, match="side is 'up'"):
        source_from_spec("hand:up", fed=True)


def test_the_network_source_takes_the_token_and_the_simulator_its_seed():
    source = source_from_spec("udp:127.0.0.1:5999", token="secret")
    assert isinstance(source, NetworkSource) and source.address == ("127.0.0.1", 5999)
    assert source._key is not None  # frames must be signed with the token
    assert isinstance(source_from_spec("simulator", seed=3), SimulatorSource)
