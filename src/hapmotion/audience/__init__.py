"""The audience at scale: one show published on NATS, every seat rendering it locally with its own settings.

* :mod:`~hapmotion.audience.wire` - subjects, the binary frame, events and the retained show description;
* :mod:`~hapmotion.audience.compact` - the compact frame (the renderer's joints, the music as a palette);
* :mod:`~hapmotion.audience.interpolation` - a seat's frames between those of a show published below its rate;
* :mod:`~hapmotion.audience.publisher` - :class:`NatsPublisherSink` (``hapmotion live ... --sink nats://HOST/SHOW``);
* :mod:`~hapmotion.audience.listener` - :func:`listen` / :func:`run_listen` (``hapmotion listen``);
* :mod:`~hapmotion.audience.seat` - a seat's settings and the stage applying them;
* :mod:`~hapmotion.audience.clock` - media time to local play time;
* :mod:`~hapmotion.audience.connection` - credentials, TLS and the description bucket;
* :mod:`~hapmotion.audience.signing` - the venue's Ed25519 signature on every message;
* :mod:`~hapmotion.audience.descriptions` - a seat following the show's description;
* :mod:`~hapmotion.audience.cue_gate` - what a seat lets through of the announced cues;
* :mod:`~hapmotion.audience.venue_config` - a venue's nats-server configuration with per-subject permissions;
* :mod:`~hapmotion.audience.server` - a local ``nats-server`` for rehearsals, tests and the benchmark.

docs/audience.md describes the wire format, the seat options and how this reaches 100,000 seats.
"""

from .connection import NatsAuth
from .listener import AudienceSource, SeatSecurity, listen, parse_show_url, run_listen
from .publisher import NatsPublisherSink, PublisherSecurity, describe_show, publishing
from .seat import Seat, SeatSink, SeatStage
from .signing import load_private_key, load_public_key
from .wire import ShowDescription, decode_frame, encode_frame, parse_description

__all__ = ["AudienceSource", "NatsAuth", "NatsPublisherSink", "PublisherSecurity", "Seat", "SeatSecurity", "SeatSink",
           "SeatStage", "ShowDescription", "decode_frame", "describe_show", "encode_frame", "listen",
           "load_private_key", "load_public_key", "parse_description", "parse_show_url", "publishing", "run_listen"]
