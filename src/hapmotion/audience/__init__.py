"""The audience at scale: one show published on NATS, every seat rendering it locally with its own settings.

* :mod:`~hapmotion.audience.wire` - subjects, the binary frame, events and the retained show description;
* :mod:`~hapmotion.audience.publisher` - :class:`NatsPublisherSink` (``hapmotion live ... --sink nats://HOST/SHOW``);
* :mod:`~hapmotion.audience.listener` - :func:`listen` / :func:`run_listen` (``hapmotion listen``);
* :mod:`~hapmotion.audience.seat` - a seat's settings and the stage applying them;
* :mod:`~hapmotion.audience.clock` - media time to local play time;
* :mod:`~hapmotion.audience.server` - a local ``nats-server`` for rehearsals, tests and the benchmark.

docs/audience.md describes the wire format, the seat options and how this reaches 100,000 seats.
"""

from .listener import AudienceSource, listen, parse_show_url, run_listen
from .publisher import NatsPublisherSink, describe_show
from .seat import Seat, SeatSink, SeatStage
from .wire import ShowDescription, decode_frame, encode_frame, parse_description

__all__ = ["AudienceSource", "NatsPublisherSink", "Seat", "SeatSink", "SeatStage", "ShowDescription",
           "decode_frame", "describe_show", "encode_frame", "listen", "parse_description", "parse_show_url",
           "run_listen"]
