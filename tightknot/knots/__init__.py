"""tightknot.knots: knot curves, topology, the study's scenes and the measurements of
Johanns et al. 2021.

Pure functions of numpy arrays (SI units inside; non-dimensional numbers only in measurement
outputs, named so). Modules:

- ``topology``: ``alexander_polynomial``, ``alexander_at_minus1``, ``knot_type``,
  ``close_open_curve``. ``knot_table``: ``knot_name``, ``candidates`` (the Alexander
  polynomials of the knots through 8 crossings).
- ``families``: ``torus_knot``, ``twist_knot`` (parametric start curves). ``catalogue``:
  the built-in knots (``BUILTIN_KNOTS``, ``open_curve``, ``ideal_l_over_d``).
- ``curves``: ``trefoil``, ``figure_eight``, ``open_trefoil``, ``open_figure_eight``,
  ``circle``, ``helix``, ``resample_uniform``, ``exclusion_arc_length``,
  ``min_nonlocal_distance``, ``scale_for_diameter``, ``check_no_overlap``.
- ``curvature``: ``bergou_curvature``, ``find_spikes``.
- ``smoothing``: ``study_smooth``, ``gaussian_smooth_points``, ``study_window``.
- ``contact_map``: ``contact_pairs``, ``partner_counts``, ``double_contact_fraction``,
  ``minrad``, ``polygonal_thickness``.
- ``closed_measures``: ``barycenter``, ``threefold_axis``, ``lay_flat``,
  ``closed_knot_profile``.  ``open_measures``: ``open_knot_measures``.
- ``measure``: ``analyze_centerline`` (all of the above on one centerline, as JSON).
- ``ideal``: ``load_ideal`` (the shipped ideal knots ``IDEAL_KNOTS``: 3_1, 4_1, 5_1, 6_1,
  8_19), ``load_ideal_trefoil``, ``load_ideal_curvature_profile``. ``ideal_overlay``:
  ``ideal_report``, ``aligned`` (an ideal knot placed on a knot's s axis).
- ``start_curve``: a user's start curve (``read_start_curve``, ``closed_from_curve``,
  ``open_from_curve``; ``tightknot tie --start``).
- ``centerline_io``: ``read_centerline``, ``parse_centerline_text``, ``write_centerline_csv``,
  ``CenterlineError``.
- ``figures``: ``plot_closed_profiles``, ``plot_contact_map``, ``plot_open_knots``.

Keys of ``analyze_centerline``'s dict. Always: closed, diameter_D0, smoothed, n_points,
length_L, rest_length_L0, stretch_L_over_L0, poisson, reduced_diameter_D, L_over_D, L_over_D0,
S (per vertex, m), s, kappa_D0 (per vertex), kappa_D0_max, kappa_D0_min, kappa_D0_mean,
alexander_polynomial, knot_determinant, knot_type, min_nonlocal_distance_over_D0,
min_nonlocal_pair_S, contact_tol, contact_s, contact_sigma, spike_threshold_kappa_D0,
curvature_spikes (list of {s_start, s_end, s_peak, kappa_peak}), n_curvature_spikes.
With smoothing: smooth_n_gauss, resample_step, smooth_window_points, length_before_smoothing.
Closed (arrays ordered by s): vertex_order, S_sorted, kappa_D0_sorted, rho, z, X_over_D0,
Y_over_D0, origin_S, axis, barycenter, inplane_spread_ratio, outer_segments_s,
inner_segments_s, double_contact_fraction, threefold ({applied, reason}: the 3-fold measures
rho, z, X, Y, axis, the segments and the spread ratio are those of a trefoil; on any other
knot they are null and s runs from vertex 0). Open (arrays in vertex order): Lambda_OC,
contact_S1, contact_S2, S_mid.
"""

from tightknot._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "analyze_centerline": ".measure",
    "read_centerline": ".centerline_io",
    "write_centerline_csv": ".centerline_io",
    "CenterlineError": ".centerline_io",
    "knot_type": ".topology",
    "alexander_polynomial": ".topology",
    "bergou_curvature": ".curvature",
    "study_smooth": ".smoothing",
    "lambda_oc": ".open_measures",
    "load_ideal_trefoil": ".ideal",
    "KnotScene": ".scenes",
    "closed_trefoil": ".scenes",
    "open_trefoil": ".scenes",
    "closed_figure_eight": ".scenes",
    "open_figure_eight": ".scenes",
    "closed_knot": ".scenes",
    "open_knot": ".scenes",
})
