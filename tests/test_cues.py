"""Cue lists: parsing (text and JSON, one-line errors), each pattern on the show's timeline, the layering rule."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hapmotion.track_files import save_track
from hapmotion.show.cues import Cue, CueList, cue_layer, layer, load_cues, pattern_rows
from hapmotion.errors import InputError
from hapmotion.layout import load_layout
from hapmotion.track import HapticTrack
from support.data import TACT

LAYOUT = load_layout()
IDS = LAYOUT.actuators
MIRROR = LAYOUT.mirror_map()


def pulse(tmp_path, name="pulse.csv", actuator="VestFront_0", level=100.0, frames=10, fps=100.0):
    """A pattern file: one motor at ``level`` for ``frames`` rows at ``fps``, then one silent row."""
    rows = np.zeros((frames + 1, 2))
    rows[:frames, 0] = level
    save_track(HapticTrack(rows, fps, (actuator, "Head_0")), tmp_path / name)
    return tmp_path / name


def test_text_cue_list_by_hand(tmp_path):
    pulse(tmp_path)
    (tmp_path / "show.cues").write_text("# time pattern options\n\n"
                                        "2.5  pulse.csv  gain=0.5 side=swap   # the pyro hit\n"
                                        "1.0 pulse.csv devices=VestBack,VestFront name=beat\n")
    cl = load_cues(tmp_path / "show.cues")
    assert [c.time_s for c in cl.cues] == [1.0, 2.5]                     # time order
    first, second = cl.cues
    assert first.devices == ("VestBack", "VestFront") and first.name == "beat" and first.place == "line 4"
    assert second.gain == 0.5 and second.side == "swap" and second.pattern == tmp_path / "pulse.csv"
    assert cl.by_name("beat") is first and cl.by_name("nope") is None


def test_json_cue_list_with_a_byte_order_mark(tmp_path):
    pulse(tmp_path)
    doc = {"cues": [{"time": 3, "pattern": "pulse.csv", "gain": 2}]}
    (tmp_path / "c.json").write_text("\ufeff" + json.dumps(doc), encoding="utf-8")
    (cue,) = load_cues(tmp_path / "c.json").cues
    assert cue.time_s == 3.0 and cue.gain == 2.0 and cue.side == "as-is" and cue.place == "cues[0]"


@pytest.mark.parametrize("text, place, problem", [
    ("1.0\n", "line 1", "expected TIME PATTERN"),
    ("x pulse.csv\n", "line 1", "the time in seconds as a number"),
    ("# c\n-1 pulse.csv\n", "line 2", "from 0 to 86400"),
    ("1 pulse.csv gain=9\n", "line 1", "the gain from 0 to 4"),
    ("1 pulse.csv gain=nan\n", "line 1", "the gain from 0 to 4"),
    ("1 pulse.csv side=up\n", "line 1", "side as-is or swap"),
    ("1 pulse.csv loud\n", "line 1", "NAME=VALUE"),
    ("1 pulse.csv colour=red\n", "line 1", "unknown field 'colour'"),
    ("1 missing.tact\n", "line 1", "expected a pattern file at"),
    ('{"cues": [{"time": 1}]}', "cues[0]", "a time and a pattern"),
    ('{"cues": [{"time": 1, "pattern": "pulse.csv", "gain": true}]}', "cues[0]", "the gain as a number"),
    ('{"cues": [{"time": 1e999999, "pattern": "pulse.csv"}]}', "cues[0]", "from 0 to 86400"),
    ('{"cues": 3}', "cues", "a list of cues"),
])
def test_bad_cue_lists_are_one_line_naming_the_place(tmp_path, text, place, problem):
    pulse(tmp_path)
    path = tmp_path / "bad.cues"
    path.write_text(text)
    with pytest.raises(InputError) as err:
        load_cues(path)
    msg = str(err.value)
    assert msg.startswith(f"{path}: {place}: ") and problem in msg and "\n" not in msg, msg


def test_deeply_nested_json_and_huge_files_are_refused(tmp_path):
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(InputError, match=r"deep\.json: expected at most 64 levels of JSON nesting \(limit depth"):
        load_cues(deep)
    big = tmp_path / "big.cues"
    big.write_text("# " + "x" * (5 << 20))
    with pytest.raises(InputError, match="under 4 MB"):
        load_cues(big)


def test_pattern_rows_resample_gain_swap_and_filter(tmp_path):
    track = HapticTrack(np.array([[100.0, 50.0], [0.0, 0.0]]), 100.0, ("VestFront_0", "Head_0"))
    notes: list[str] = []
    cue = Cue(0.0, tmp_path / "p.csv", gain=0.5, place="line 1")
    rows = pattern_rows(track, fps=50.0, actuators=IDS, mirror_map=MIRROR, cue=cue, notes=notes)
    assert rows.shape == (1, len(IDS))                       # 20 ms at 100 fps -> one 50 fps row
    assert rows[0, IDS.index("VestFront_0")] == 50.0 and rows.sum() == 50.0
    assert notes == ["p.csv (line 1): no Head in the show's layout; left out"]
    swapped = pattern_rows(track, fps=100.0, actuators=IDS, mirror_map=MIRROR,
                           cue=Cue(0.0, tmp_path / "p.csv", side="swap"))
    assert swapped[0, IDS.index("VestFront_3")] == 100.0 and swapped[0].sum() == 100.0   # col 0 -> col 3
    none = pattern_rows(track, fps=100.0, actuators=IDS, mirror_map=MIRROR,
                        cue=Cue(0.0, tmp_path / "p.csv", devices=("VestBack",)))
    assert not none.any()


def test_cue_layer_places_each_cue_and_adds_energy(tmp_path):
    path = pulse(tmp_path, level=60.0, frames=10, fps=100.0)
    cues = CueList([Cue(0.5, path), Cue(0.55, path, gain=80 / 60)], tmp_path / "c.cues")
    energy = cue_layer(cues, fps=100.0, n_frames=100, actuators=IDS, mirror_map=MIRROR)
    col = IDS.index("VestFront_0")
    assert energy[:50].sum() == 0.0 and energy[65:].sum() == 0.0
    assert energy[52, col] == pytest.approx(0.36)                # the first cue alone
    assert energy[57, col] == pytest.approx(0.36 + 0.64)         # both: 60 and 80 in energy
    assert energy[62, col] == pytest.approx(0.64)                # the second alone
    assert np.count_nonzero(energy.sum(axis=0)) == 1
    late = CueList([Cue(2.0, path)], tmp_path / "c.cues")
    assert not cue_layer(late, fps=100.0, n_frames=100, actuators=IDS, mirror_map=MIRROR).any()


def test_layering_rule_by_hand():
    show = np.zeros((2, len(IDS)))
    show[:, 0] = 60.0
    cue = np.zeros_like(show)
    cue[0, 0] = 0.64                                              # an 80 % cue on the same motor
    cue[1, 5] = 0.64                                              # and on another one
    out = layer(show, cue, power_limit=None)
    assert out[0, 0] == pytest.approx(100.0)                      # sqrt(0.36 + 0.64)
    assert out[1, 0] == pytest.approx(60.0) and out[1, 5] == pytest.approx(80.0)
    loud = layer(np.full((1, len(IDS)), 90.0), np.full((1, len(IDS)), 0.5), power_limit=0.75 * len(IDS))
    assert ((loud / 100) ** 2).sum() == pytest.approx(0.75 * len(IDS))   # the show's power limit still holds
    assert loud.max() <= 100.0


def test_real_designer_pattern_as_a_cue(tmp_path):
    """bHaptics' Heartbeat pattern (a Designer vest file) cued at 1 s lands on the vest from then on."""
    heart = TACT / "FeedbackFiles_Vest_Heartbeat.tact"
    (tmp_path / "c.cues").write_text(f"1.0 {heart}\n")
    cues = load_cues(tmp_path / "c.cues")
    energy = cue_layer(cues, fps=50.0, n_frames=500, actuators=IDS, mirror_map=MIRROR)
    assert not energy[:50].any() and energy[50:].any()
    vest = [i for i, a in enumerate(IDS) if a.startswith("Vest")]
    assert energy[:, vest].sum() == pytest.approx(energy.sum())


def test_total_cue_rows_are_bounded_by_the_frames_limit(tmp_path):
    """By hand: a 11-row pattern cued 3 times is 33 rows; a frames limit of 40 admits 3 cues and refuses a 4th,
    naming the cue where the total went over, the limit and how to raise it."""
    pulse(tmp_path)
    (tmp_path / "three.cues").write_text("0 pulse.csv\n1 pulse.csv\n2 pulse.csv\n")
    assert len(load_cues(tmp_path / "three.cues", limits={"frames": 40}).cues) == 3
    (tmp_path / "four.cues").write_text("0 pulse.csv\n1 pulse.csv\n2 pulse.csv\n3 pulse.csv\n")
    with pytest.raises(InputError) as info:
        load_cues(tmp_path / "four.cues", limits={"frames": 40})
    assert str(info.value) == (f"{tmp_path / 'four.cues'}: line 4: expected at most 40 pattern rows in all cues "
                               "together (each cue counts its pattern's rows) (limit frames; raise it with --limit "
                               "frames=N), found 44")


def test_a_hundred_cues_of_a_one_hour_pattern_are_refused_at_the_default_limits(tmp_path):
    """The case that took 28-41 s to render: 100 cues of one hour at 50 fps are 18 million rows; the list is refused
    at its third cue (540,000 rows > 500,000) after reading the pattern once."""
    hour = np.zeros((180_000, 2))
    hour[::50, 0] = 50.0
    save_track(HapticTrack(hour, 50.0, ("VestFront_0", "VestBack_0")), tmp_path / "hour.npz")
    (tmp_path / "show.json").write_text(json.dumps({"cues": [{"time": k, "pattern": "hour.npz"} for k in range(100)]}))
    with pytest.raises(InputError, match=r"cues\[2\]: expected at most 500000 pattern rows .* found 540000"):
        load_cues(tmp_path / "show.json")


def test_a_real_pattern_cued_many_times_stays_within_the_limits(tmp_path):
    """A real Designer pattern cued every 2 s for ten minutes is read once and laid on the timeline."""
    cue_text = "".join(f"{2 * k} {TACT / 'FeedbackFiles_Vest_ArrowHit.tact'}\n" for k in range(300))
    (tmp_path / "beats.cues").write_text(cue_text)
    cues = load_cues(tmp_path / "beats.cues")
    assert len(cues.patterns) == 1 and len(cues.cues) == 300
    energy = cue_layer(cues, fps=50.0, n_frames=50 * 600, actuators=IDS, mirror_map=MIRROR)
    assert energy.any() and np.isfinite(energy).all()


def test_a_pattern_name_too_long_for_the_file_system_is_a_one_line_error(tmp_path):
    (tmp_path / "long.cues").write_text(f"0 {'p' * 5000}.csv\n")
    with pytest.raises(InputError, match=r"line 1: expected a pattern file name, found one the system refuses"):
        load_cues(tmp_path / "long.cues")
