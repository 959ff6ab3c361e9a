"""Cyclone DDS set up as ROS 2 expects: domains, ``rt/`` topics, and the QoS of ROS 2's profiles."""

from __future__ import annotations

import time
from typing import Any

from scanlines.errors import ParameterError
from scanlines.untrusted import quote

__all__ = [
    "LOOPBACK_CONFIG",
    "RECEIVE_BUFFER",
    "default_qos",
    "latched_qos",
    "loopback_config",
    "participant",
    "prepare",
    "ros_topic",
    "sensor_data_qos",
    "take_serialized",
    "wait_for_match",
]

#: The socket receive buffer the loopback configuration asks for (Linux grants at most
#: ``net.core.rmem_max``). Cyclone's own request, 1 MiB, overflows on the burst of
#: fragments of a 4 MB scan (a million beams), which best effort then loses whole.
RECEIVE_BUFFER = "8MB"


def loopback_config(receive_buffer: str | None = RECEIVE_BUFFER) -> str:
    """Cyclone DDS confined to the loopback interface: unicast discovery to 127.0.0.1
    (``lo`` has no multicast), so nothing leaves the machine; asking for a socket receive
    buffer of ``receive_buffer`` (``None``: Cyclone's default). Cyclone still binds its
    discovery and data receive sockets to every interface (eclipse-cyclonedds #1923): a
    remote host's datagrams reach them, though it cannot complete discovery (README)."""
    internal = (
        ""
        if receive_buffer is None
        else f'<Internal><SocketReceiveBufferSize max="{receive_buffer}"/></Internal>'
    )
    return f"""<CycloneDDS><Domain id="any"><General>
<Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces>
<AllowMulticast>false</AllowMulticast></General>
<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>30</MaxAutoParticipantIndex>
<Peers><Peer address="127.0.0.1"/></Peers></Discovery>{internal}</Domain></CycloneDDS>"""


#: The configuration of ``--loopback`` (:func:`loopback_config`).
LOOPBACK_CONFIG = loopback_config()

_DOMAINS: dict[int, Any] = {}


def participant(domain_id: int, *, loopback: bool = False) -> Any:
    """A DDS participant on ROS domain ``domain_id`` (``ROS_DOMAIN_ID``); ``loopback``:
    on 127.0.0.1 only, else as ``CYCLONEDDS_URI`` (or Cyclone's default) configures it."""
    from cyclonedds.domain import Domain, DomainParticipant

    if not 0 <= domain_id <= 232:
        raise ParameterError(f"--domain-id must be within 0..232 (ROS 2), got {domain_id}")
    if loopback and domain_id not in _DOMAINS:
        _DOMAINS[domain_id] = Domain(domain_id, LOOPBACK_CONFIG)
    return DomainParticipant(domain_id)


def prepare(*kinds: type) -> None:
    """Build the serialisers of message types now: Cyclone builds each on first use, which
    takes long enough (a tenth of a second and more) for a sensor-data reader to lose scans."""
    for kind in kinds:
        kind.deserialize(kind().serialize())


def ros_topic(name: str) -> str:
    """The DDS topic of ROS 2 topic ``name``: ``/scan`` and ``scan`` are ``rt/scan``."""
    stripped = name.strip("/")
    if not stripped or any(not (c.isalnum() or c in "_/") for c in stripped):
        raise ParameterError(f"not a ROS 2 topic name: {quote(name)}")
    return f"rt/{stripped}"


def sensor_data_qos(depth: int = 5) -> Any:
    """ROS 2's sensor-data profile: best effort, volatile, keep last ``depth``."""
    from cyclonedds.core import Policy, Qos

    return Qos(
        Policy.Reliability.BestEffort, Policy.Durability.Volatile, Policy.History.KeepLast(depth)
    )


def default_qos(depth: int = 10) -> Any:
    """ROS 2's default profile: reliable, volatile, keep last ``depth`` (a default ROS 2
    subscriber, best effort or reliable, accepts it)."""
    from cyclonedds.core import Policy, Qos
    from cyclonedds.util import duration

    return Qos(
        Policy.Reliability.Reliable(duration(milliseconds=100)),
        Policy.Durability.Volatile,
        Policy.History.KeepLast(depth),
    )


def latched_qos(depth: int = 1) -> Any:
    """ROS 2's "latched" profile (``/map``, ``/tf_static``): reliable, transient local, keep
    last ``depth``: a subscriber that comes later still gets the last ``depth`` messages."""
    from cyclonedds.core import Policy, Qos
    from cyclonedds.util import duration

    return Qos(
        Policy.Reliability.Reliable(duration(milliseconds=100)),
        Policy.Durability.TransientLocal,
        Policy.History.KeepLast(depth),
    )


def take_serialized(reader: Any, count: int) -> list[tuple[bytes, Any]]:
    """Up to ``count`` samples off ``reader`` as Cyclone holds them: each sample's CDR bytes
    (encapsulation header first) with its ``SampleInfo``, not decoded. ``DataReader.take``
    decodes every sample it takes, so one that does not decode (a ``frame_id`` that is not
    UTF-8) raises out of the take and loses the others taken with it; decoded one by one,
    each sample fails alone. (The binding's own take, without the decoding step.)"""
    from cyclonedds._clayer import ddspy_take
    from cyclonedds.core import DDSException, InstanceState, SampleState, ViewState

    mask = SampleState.Any | ViewState.Any | InstanceState.Any
    taken = ddspy_take(reader._ref, mask, count)
    if isinstance(taken, int):
        raise DDSException(taken, f"Occurred while taking data in {reader!r}")
    return taken


def wait_for_match(entity: Any, timeout: float) -> bool:
    """Wait up to ``timeout`` seconds until a writer has a subscriber or a reader a
    publisher; whether it has."""
    matched = getattr(entity, "get_matched_subscriptions", None) or entity.get_matched_publications
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if matched():
            return True
        time.sleep(0.02)
    return bool(matched())
