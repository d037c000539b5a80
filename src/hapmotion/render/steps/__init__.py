"""The paper's motion pipeline (Jung et al., Virtual Reality 28:13, 2024, Section 4), one compiled module per step.

=====  ==================================================================  =================
step   what                                                                module
=====  ==================================================================  =================
1      joints in, missing ones held                                        ``held_joints``
2      J_T and the body frame                                              ``hapmotion.body.frame``
3-4    hand accelerations, thresholds, the active-joint choice             ``choice``
5      motion salient triangle, weights, dynamic point (Eq. 1)             ``triangle``
6      target point, ray, 3D warping, 13 cm / 185 cm rules, chart (u, v)   ``warping``
7-8    intensity filter (Eq. 2), boost, maximum level, drive               ``intensity``
8      phantom split                                                       ``phantom``
out    mirror, dead zone, per-actuator release                             ``output``
=====  ==================================================================  =================

``hapmotion.render.kernel.render_frames`` runs them in order, frame by frame. Every function is ``@njit(cache=True)``
and works on plain arrays and scalars, so each can be called from Python (and tested) on its own.

numba caches a compiled function together with everything it calls, but checks only the caller's own file for
changes: after editing a module here, delete the stale caches (``find src -name __pycache__ -exec rm -rf {} +``).
``tests/test_render_steps.py`` renders a clip with and without compilation and fails when the cache is stale.
"""
