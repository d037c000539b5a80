"""A synchronised seat's played frames: kept for its last ``--sync-max-delay`` and handed back when the delay it plays
at moves later (a lock, a jump), so that the vest goes on in step instead of pausing for the difference. Worked by
hand: frames at media times 0, 0.1, ... played at offset 0 (local time = media time), then the delay moves."""

from __future__ import annotations

from hapmotion.audience.played_frames import PlayedFrames
from hapmotion.audience.sync_tracker import GATE_S


def test_a_move_is_a_lock_a_jump_or_a_return_to_searching_never_the_filter_s_small_corrections():
    played: PlayedFrames[int] = PlayedFrames(10)
    assert not played.moved(None)                 # searching, as at the start
    assert played.moved(1.5)                      # locked on 1.5 s
    assert not played.moved(1.5 + GATE_S / 2)     # the filter's corrections...
    assert not played.moved(1.5 + GATE_S * 0.9)   # ...however many, measured from the last move
    assert played.moved(1.5 + GATE_S * 1.1)       # past the gate from 1.5: a move
    assert played.moved(2.6)                      # a jump
    assert played.moved(None)                     # back to searching
    assert not played.moved(None)


def test_the_frames_whose_new_time_is_still_to_come_come_back_once_in_their_order():
    played: PlayedFrames[float] = PlayedFrames(100)
    for k in range(30):                # media times 0.0 .. 2.9 s, played at offset 0 by local time 3.0
        played.keep(k / 10)
    assert played.moved(None) is False and played.moved(1.5)
    # at offset 1.5 s, media time m plays at m + 1.5: after now (3.0) for m > 1.5, that is 1.6 .. 2.9
    again = played.again(lambda m: m + 1.5, 3.0)
    assert again == [k / 10 for k in range(16, 30)]
    assert len(played) == 16
    assert played.again(lambda m: m + 1.5, 3.0) == []  # handed back once
    # frames that play nowhere (a seat that plays nothing while unlocked) never come back
    assert played.again(lambda m: None, 0.0) == []


def test_only_the_last_capacity_frames_are_kept():
    played: PlayedFrames[int] = PlayedFrames(5)
    for k in range(12):
        played.keep(k)
    assert len(played) == 5
    assert played.again(lambda k: 1.0, 0.0) == [7, 8, 9, 10, 11]
