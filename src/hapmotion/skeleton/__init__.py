"""Skeleton conventions shared by the file readers and the live sources.

:mod:`.joints` (the 32 canonical joints, their parents and the joints the renderer reads), :mod:`.naming` (the
naming schemes of the skeletons we meet, Unity's humanoid included, as tables, and the generic matcher),
:mod:`.spine` (the spine joints placed by position), :mod:`.humanoid` (Unity's ``HumanBodyBones`` and their
hierarchy, as sent by VMC) and :mod:`.derived` (joints a skeleton lacks, derived from the ones it has). Nothing
here reads a file or a socket.
"""
