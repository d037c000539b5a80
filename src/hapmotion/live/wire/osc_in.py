"""OSC in: skeleton frames from OSC messages (:mod:`.osc_packet` reads the datagrams).

Address scheme, prefix ``/hapmotion`` (settable; docs/live.md has the full description):

* ``/hapmotion/skeleton [seq:int, t:float,] x0 y0 z0 ... x31 y31 z31`` - one message, all 32 canonical joints in
  Azure Kinect order, metres, +Y up (96 floats, optionally preceded by a sequence number and a sender time);
* ``/hapmotion/joint/<JOINT_NAME> [seq:int, t:float,] x y z`` - one joint; a frame is made of the joint messages
  that precede ``/hapmotion/frame [seq:int, t:float]``, or of those inside one OSC bundle, or (when the joint
  messages carry a seq) of those that share a seq.
"""

from __future__ import annotations

import struct
from typing import Any, Optional

import numpy as np

from ...skeleton.joints import N_JOINTS
from ..frames import SkeletonFrame, joint_index
from ..hygiene import Faults, is_number, seq_value, time_value
from .osc_address import OSC_PREFIX, normalize_prefix
from .osc_packet import read_osc


_TAGS_XYZ = b"," + b"f" * (3 * N_JOINTS)
_TAGS_SEQ_T32 = b",if" + b"f" * (3 * N_JOINTS)
_TAGS_SEQ_T64 = b",id" + b"f" * (3 * N_JOINTS)


def _osc_string(text: str) -> bytes:
    """``text`` as an OSC-string: its bytes (UTF-8, as python-osc writes and reads them), NUL-terminated, padded
    with NULs to a multiple of 4 bytes."""
    raw = text.encode("utf-8")
    return raw + b"\0" * (4 - len(raw) % 4)


class OscSkeletonDecoder:
    """Turns OSC datagrams into :class:`SkeletonFrame` s (address scheme above).

    Stateful only for per-joint messages, which are gathered into a pending frame until it is closed. The pending
    frame holds at most 32 joints, so a sender that never closes its frames cannot grow memory.
    """

    def __init__(self, faults: Faults, prefix: str = OSC_PREFIX):
        self.faults = faults
        prefix = normalize_prefix(prefix)
        self.addr_skeleton = prefix + "/skeleton"
        self.addr_frame = prefix + "/frame"
        self.addr_joint = prefix + "/joint/"
        self._pending: Optional[np.ndarray] = None
        self._pending_seq: Optional[int] = None
        self._pending_t: Optional[float] = None
        self._skeleton_head = _osc_string(self.addr_skeleton)

    def feed(self, dgram: bytes, received: float) -> list[SkeletonFrame]:
        """Decode one datagram; return the frames it completes (usually zero or one)."""
        if dgram.startswith(self._skeleton_head):
            frame = self._skeleton_fast(dgram, received)
            if frame is not None:
                return [frame]
        packet = read_osc(dgram, self.faults)
        out: list[SkeletonFrame] = []
        joints_seen = False
        for msg in packet.messages:
            address, params = msg.address, msg.params
            if address == self.addr_skeleton:
                frame = self._skeleton(params, received)
                if frame is not None:
                    out.append(frame)
            elif address.startswith(self.addr_joint):
                joints_seen = True
                self._joint(address[len(self.addr_joint):], params, received, out)
            elif address == self.addr_frame:
                self._close(params, received, out)
            else:
                self.faults.add("unknown_address", f"OSC address {address!r}, expected {self.addr_skeleton}, "
                                                   f"{self.addr_joint}<JOINT> or {self.addr_frame}")
        # A bundle of joint messages is one frame even without a closing /frame message.
        if joints_seen and self._pending is not None and packet.bundle:
            self._close([], received, out)
        return out

    def _skeleton(self, params: list[Any], received: float) -> Optional[SkeletonFrame]:
        n = len(params)
        if n not in (3 * N_JOINTS, 3 * N_JOINTS + 2):
            self.faults.add("wrong_joint_count", f"{self.addr_skeleton} with {n} arguments, expected "
                                                 f"{3 * N_JOINTS} coordinates (32 joints), optionally after seq and t")
            return None
        if not all(is_number(v) for v in params):
            self.faults.add("malformed", f"{self.addr_skeleton} with a non-numeric argument")
            return None
        seq = t = None
        if n == 3 * N_JOINTS + 2:
            seq, t = seq_value(params[0]), time_value(params[1])
            params = params[2:]
        pos = np.array(params, dtype=np.float64).reshape(N_JOINTS, 3)
        return SkeletonFrame(pos, seq, t, received)

    def _skeleton_fast(self, dgram: bytes, received: float) -> Optional[SkeletonFrame]:
        """The common skeleton message read straight from its bytes, or None to leave it to the general reader.

        A sender streaming at 60 Hz sends one ``/hapmotion/skeleton`` message a frame with type tags ``,f*96``,
        ``,if f*96`` or ``,id f*96`` (seq int32, time float32 or float64; the OSC 1.0 specification's big-endian
        encodings). python-osc decodes such a message argument by argument (about 40 us); here the 96 coordinates
        are one numpy view (a few us). The values are the ones python-osc returns (float32 widened to float64);
        anything else (other tags, a wrong length, a bundle) goes through :func:`read_osc`, which counts faults.
        """
        start = len(self._skeleton_head)
        end = dgram.find(b"\0", start)
        if end < 0:
            return None
        tags = dgram[start:end]
        args = start + (end - start) // 4 * 4 + 4  # the tag string is padded to a multiple of 4 with at least one NUL
        if tags == _TAGS_XYZ:
            seq = t = None
        elif tags == _TAGS_SEQ_T32 and len(dgram) == args + 8 + 4 * 3 * N_JOINTS:
            seq_raw, t_raw = struct.unpack_from(">if", dgram, args)
            seq, t = seq_value(seq_raw), time_value(t_raw)
            args += 8
        elif tags == _TAGS_SEQ_T64 and len(dgram) == args + 12 + 4 * 3 * N_JOINTS:
            seq_raw, t_raw = struct.unpack_from(">id", dgram, args)
            seq, t = seq_value(seq_raw), time_value(t_raw)
            args += 12
        else:
            return None
        if len(dgram) != args + 4 * 3 * N_JOINTS:
            return None
        with np.errstate(invalid="ignore"):  # a signalling NaN sent as a joint: non-finite joints are refused later
            pos = np.frombuffer(dgram, dtype=">f4", count=3 * N_JOINTS, offset=args).astype(np.float64)
        return SkeletonFrame(pos.reshape(N_JOINTS, 3), seq, t, received)

    def _joint(self, name: str, params: list[Any], received: float, out: list[SkeletonFrame]) -> None:
        try:
            j = joint_index(name)
        except KeyError:
            self.faults.add("unknown_joint", f"joint name {name!r}, expected a canonical name such as HAND_LEFT")
            return
        if len(params) not in (3, 5) or not all(is_number(v) for v in params):
            self.faults.add("malformed", f"{self.addr_joint}{name} needs x y z (or seq t x y z) numbers, "
                                         f"found {len(params)} arguments")
            return
        seq = t = None
        if len(params) == 5:
            seq, t = seq_value(params[0]), time_value(params[1])
            params = params[2:]
            if self._pending is not None and seq is not None and self._pending_seq is not None \
                    and seq != self._pending_seq:
                self._close([], received, out)  # a new seq closes the previous frame
        if self._pending is None:
            self._pending = np.full((N_JOINTS, 3), np.nan)
        if seq is not None:
            self._pending_seq = seq
        if t is not None:
            self._pending_t = t
        self._pending[j] = params

    def _close(self, params: list[Any], received: float, out: list[SkeletonFrame]) -> None:
        if params:
            if len(params) != 2 or not all(is_number(v) for v in params):
                self.faults.add("malformed", f"{self.addr_frame} takes seq and t, found {len(params)} arguments")
            else:
                self._pending_seq, self._pending_t = seq_value(params[0]), time_value(params[1])
        if self._pending is not None:
            out.append(SkeletonFrame(self._pending, self._pending_seq, self._pending_t, received))
        self._pending = None
        self._pending_seq = None
        self._pending_t = None
