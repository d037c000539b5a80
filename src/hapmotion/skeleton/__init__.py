"""Skeleton conventions shared by the file readers and the live sources.

:mod:`.joints` (the 32 canonical joints, their parents and the joints the renderer reads), :mod:`.naming` (the
naming schemes of the skeletons we meet, matched onto those joints, and the spine assigned by position),
:mod:`.humanoid` (Unity's ``HumanBodyBones``, as sent by VMC) and :mod:`.derived` (joints a skeleton lacks,
derived from the ones it has). Nothing here reads a file or a socket.
"""
