"""``hapmotion.render`` as it was before its kernel read the motion's own array: the render joints gathered into a
``(T, 7, 3)`` copy for the frame loop, the body sized from whole-array body frames
(``previous_show.body_from_motion``) and the track built by the constructor with its full range check. Kept only so
that tests can check the faster path gives the same bytes."""

from __future__ import annotations

import numpy as np

from hapmotion.layout import load_layout
from hapmotion.renderer import packed
from hapmotion.renderer.kernel import render_frames
from hapmotion.renderer.params import get_preset
from hapmotion.renderer.renderer import pack_params
from hapmotion.skeleton.joints import JOINT_INDEX, RENDER_JOINTS
from hapmotion.track import HapticTrack

from .previous_show import body_from_motion

RENDER_IDX = np.array([JOINT_INDEX[n] for n in RENDER_JOINTS], dtype=np.intp)


def render_gathered(motion, method: str = "mst", preset: str = "felt") -> HapticTrack:
    """The rows and debug ``hapmotion.render(motion, method, preset)`` made from a gathered copy of the joints."""
    params = get_preset(preset)
    layout = load_layout()
    body = body_from_motion(motion)
    joints = np.take(np.asarray(motion.positions, dtype=np.float64), RENDER_IDX, axis=1)  # (T, 7, 3), a copy
    n, n_act = joints.shape[0], layout.n_actuators
    out = np.zeros((n, n_act))
    dbg_f = np.zeros((n, packed.N_DEBUG_F))
    dbg_i = np.zeros((n, packed.N_DEBUG_I), dtype=np.int8)
    mirror = layout.mirror_map() if params.mirror else np.arange(n_act)
    render_frames(joints, np.arange(len(RENDER_JOINTS), dtype=np.intp), pack_params(params, method, motion.fps),
                  body.as_array(), layout.chart_table(), mirror, packed.new_state(n_act), out, dbg_f, dbg_i)
    debug = {"level": dbg_f[:, packed.D_LEVEL], "dynamic_point": dbg_f[:, packed.D_DP:packed.D_DP + 3],
             "chart": dbg_i[:, packed.DI_CHART]}
    return HapticTrack(intensities=out, fps=motion.fps, actuators=layout.actuators, layout=layout.name,
                       meta={"body": body.to_dict()}, debug=debug)
