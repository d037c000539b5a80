"""The paper's motion pipeline (Jung et al., Virtual Reality 28:13, 2024, Section 4), one compiled module per step.

=====  ====================================================================  ==========================
step   what                                                                  where
=====  ====================================================================  ==========================
1      joints in, missing ones held                                          ``held_joints``
2      J_T and the body frame                                                ``hapmotion.body.frame``
3      the hands' accelerations relative to J_T                              ``choice``
4      thresholds, active hands, the choice                                  ``choice``
5      motion salient triangle, weights, dynamic point (Eq. 1)               ``triangle``
6      target point, ray, 3D warping, 13 cm / 185 cm rules, chart (u, v)     ``warping``
7      intensity filter (Eq. 2)                                              ``intensity``
8      boost, maximum level, drive; phantom split                            ``intensity``, ``phantom``
out    mirror (step 6), dead zone, per-actuator release                      ``output``
=====  ====================================================================  ==========================

``hapmotion.renderer.kernel.render_frames`` runs them in order, frame by frame; docs/algorithm.md names every function
and gives the paper's text and our reading for each step. Every function is ``@njit(cache=True)`` on plain arrays
and scalars, so each can also be called (and tested) from Python on its own. The small ones are compiled
``inline="always"`` into the loop, which then runs as fast as one long function.

numba caches a compiled function together with everything it calls but checks only the caller's own file for
changes: after editing a module here, delete the stale caches (``find src -name __pycache__ -exec rm -rf {} +``).
``tests/test_render_steps.py`` renders a clip with and without compilation and fails when a cache is stale.
"""
