"""Who may send, sans-I/O: sender allow-lists, the shared token, per-sender budgets, the exposure line."""

from __future__ import annotations

import pytest

from hapmotion.errors import UsageError
from hapmotion.live.access import (SenderAllowList, SenderBudgets, bearer_token, burst_for, exposure_line,
                                   is_loopback, token_matches)


def test_allow_list_of_addresses_and_networks():
    allow = SenderAllowList.parse(["192.168.1.20, 10.1.0.0/16", "::1"])
    assert allow.allows("192.168.1.20") and allow.allows("10.1.255.3") and allow.allows("::1")
    assert allow.allows("::ffff:10.1.0.7")          # an IPv4 sender seen through a dual-stack socket
    assert not allow.allows("192.168.1.21") and not allow.allows("10.2.0.1") and not allow.allows("garbage")
    assert allow.describe() == "192.168.1.20, 10.1.0.0/16, ::1"
    everyone = SenderAllowList.parse([])
    assert not everyone and everyone.allows("203.0.113.9")
    with pytest.raises(UsageError, match="--allow-sender '10.0.0.300'"):
        SenderAllowList.parse(["10.0.0.1,10.0.0.300"])


def test_allow_list_memory_is_bounded_under_spoofed_addresses():
    allow = SenderAllowList.parse(["10.0.0.1"])
    for k in range(10_000):
        allow.allows(f"172.16.{k // 256}.{k % 256}")
    assert len(allow._cache) <= 4096 and allow.allows("10.0.0.1")


def test_token_checks():
    assert token_matches("s3cret", "s3cret")
    assert not token_matches("s3cret", "s3creT") and not token_matches("s3cret", None)
    assert not token_matches("s3cret", "s3cret ") and not token_matches("s3cret", "")
    assert token_matches("päss", "päss")  # any text, compared as UTF-8 bytes
    assert bearer_token("Bearer abc") == "abc" and bearer_token("bearer  abc ") == "abc"
    assert bearer_token("Basic abc") is None and bearer_token("Bearer") is None and bearer_token(None) is None


def test_each_sender_has_its_own_budget():
    b = SenderBudgets(rate=100.0, burst=10.0, max_senders=3)
    assert [b.admit("flooder", 0.0) for _ in range(12)].count(None) == 10       # its burst, then refused
    assert b.admit("flooder", 0.0) == "flood"
    assert all(b.admit("performer", 0.0) is None for _ in range(10))            # untouched by the flood
    assert sum(b.admit("performer", 0.05) is None for _ in range(50)) == 5      # 50 ms at 100/s


def test_senders_beyond_the_limit_wait_for_a_silent_one():
    b = SenderBudgets(rate=100.0, burst=10.0, max_senders=2, idle_s=2.0)
    assert b.admit("a", 0.0) is None and b.admit("b", 0.0) is None
    assert b.admit("c", 1.0) == "too_many_senders"
    assert b.admit("a", 1.5) is None                 # a keeps sending ...
    b.useful("a", 1.5)                               # ... usable messages: it keeps its place
    assert b.admit("c", 2.5) is None                 # b silent for 2.5 s: c takes its place
    assert b.admit("b", 2.6) == "too_many_senders" and b.senders == 2 and b.evicted == 1
    with pytest.raises(UsageError):
        SenderBudgets(1.0, 1.0, max_senders=0)


def test_exposure_line_and_loopback():
    assert is_loopback("127.0.0.1") and is_loopback("127.0.0.2") and is_loopback("::1") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.10") and not is_loopback("stage.local")
    assert burst_for(60.0) == 240.0 and burst_for(10.0) == 64.0
    line = exposure_line("0.0.0.0", SenderAllowList.parse(["10.0.0.5"]), max_senders=4, budget=240.0,
                         origins=["https://show.example"], token="x")
    assert line == ("reachable from every network interface; senders: 10.0.0.5; token: required (Authorization: "
                    "Bearer header or ?token=); browser pages: https://show.example; at most 4 senders, "
                    "240 messages/s each")
    assert exposure_line("127.0.0.1", SenderAllowList(), max_senders=8, budget=2400.0) == (
        "reachable from this machine only; senders: any address; at most 8 senders, 2400 messages/s each")


def test_a_sender_of_junk_gives_its_place_to_the_performer():
    """By hand: two places. j sends one junk message a second (admitted, never useful), p1 streams usable frames.
    A performer p2 arriving at 3.0 s takes j's place (nothing usable for over 2 s); p1 keeps its own."""
    b = SenderBudgets(rate=100.0, burst=10.0, max_senders=2, idle_s=2.0)
    for t in (0.0, 1.0, 2.0, 2.9):
        assert b.admit("j", t) is None
        assert b.admit("p1", t) is None
        b.useful("p1", t)
    assert b.admit("p2", 1.5) == "too_many_senders"  # j is still within its first 2 s
    assert b.admit("p2", 3.0) is None and b.evicted == 1
    assert b.admit("j", 3.1) == "too_many_senders"   # the junk sender is the one that went


def test_a_bundle_counts_for_what_it_holds():
    """A VMC source's default budget at 60 fps: 7680 messages/s in bursts of 1024. A 4.3 KB bundle (one frame of
    55 bones) costs 67.5 messages, so 15 pass at once and a 16th waits; a 60 KB bundle costs 937.5: one passes
    with a full bucket, a second right after it does not, where each would have cost 1 before."""
    from hapmotion.live.sources import VmcSource
    from hapmotion.live.wire.vmc_in import VmcDecoder

    frame = b"#bundle\0" + b"\0" * (4320 - 8)
    big = b"#bundle\0" + b"\0" * (60_000 - 8)
    assert VmcDecoder.cost(frame) == 67.5 and VmcDecoder.cost(big) == 937.5
    assert VmcDecoder.cost(b"/VMC/Ext/T\0\0") == 1.0
    rate, burst = VmcSource().default_budget(60.0)
    assert (rate, burst) == (7680.0, 1024.0)
    b = SenderBudgets(rate, burst, max_senders=1)
    assert [b.admit("s", 0.0, VmcDecoder.cost(frame)) for _ in range(16)] == [None] * 15 + ["flood"]
    assert b.admit("s", 10.0, VmcDecoder.cost(big)) is None and b.admit("s", 10.0, VmcDecoder.cost(big)) == "flood"
