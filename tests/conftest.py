"""Shared test set-up: Agg backend, figures closed after each test, the ``slow`` marker.

Two tiers (README, "Development"; docs/developer.md): ``make test`` runs every test (the suite
CI runs, about 8 minutes on 2 cores); ``make test-fast`` leaves out the tests marked ``slow``
(listed in ``SLOW`` below) for the inner loop, in under 2 minutes. The long convergence and
accuracy studies are validation benchmarks (``make bench-validation``, benchmarks/accuracy.md);
tests/test_convergence.py checks the observed orders on a short refinement ladder by default.
"""

import os

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("NUMBA_BOUNDSCHECK", "0")


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


# The tests that took 1.5 s or more (all their parameters together) in
# ``pytest --durations=0`` of the whole suite (2026-12-02, 2 shared cores: 366 s of test time
# in all, these 61 functions 309 s of it): marked ``slow``, so ``make test-fast``
# (``-m "not slow"``) leaves them out. Listed here rather than decorated in each file, so the
# tiers are one list; a slow test you add belongs here (tests/test_tiers.py checks that every
# entry still names a test).
SLOW = {
    "test_answer.py": (
        "test_thresholds_in_e_far_and_e_wet_bracket_the_change",
        "test_an_approach_too_slow_for_the_outer_flow_stops_before_x0",
    ),
    "test_cavitation.py": (
        "test_rigid_separation_force_and_cavity_converge_to_the_closed_form",
        "test_whole_collisions_converge_under_refinement",
    ),
    "test_dem.py": (
        "test_export_dem_from_a_sweep_store",
        "test_fit_range_fits_only_there_and_reports_every_row",
        "test_store_with_a_further_axis_groups_by_it",
    ),
    "test_docs.py": (
        "test_python_example_runs_from_a_copy_of_the_examples",
    ),
    "test_far_field.py": (
        "test_cli_outer_bad_input_exits_2_with_one_line",
        "test_cli_run_json_has_e_far",
        "test_e_far_solves_the_equation_of_motion_with_added_mass",
        "test_history_force_lowers_e_far_more_in_a_lighter_sphere",
        "test_history_restitution_from_far_outer_starts",
        "test_history_restitution_without_the_history_force_is_e_far",
        "test_resistance_integral_against_adaptive_quadrature",
    ),
    "test_hostile.py": (
        "test_a_chunk_that_only_decoding_finds_is_found_before_a_sweep_writes",
        "test_a_damaged_coordinate_is_listed_refused_and_rewritten",
        "test_a_full_disk_at_the_journal_cuts_it_back_to_whole_records",
        "test_a_full_disk_while_merging_keeps_every_finished_scene",
        "test_a_full_stdout_is_one_line",
        "test_a_peer_that_is_no_scheduler_is_refused_within_the_timeout",
        "test_a_real_ctrl_c_during_the_compiled_solve_is_exit_130_one_line",
        "test_a_scheduler_killed_mid_sweep_is_one_line_and_keeps_finished_scenes",
        "test_a_scheduler_without_workers_is_reported_after_the_wait",
        "test_a_sweep_on_a_real_full_disk",
        "test_a_sweep_recomputes_damaged_cells_and_nothing_else",
        "test_another_sweep_file_needs_add_sweep_and_is_recorded",
        "test_bad_input_gives_one_line_and_changes_nothing",
        "test_ctrl_c_is_exit_130_one_line_and_keeps_every_finished_scene",
        "test_a_local_workers_own_log_lines_never_reach_the_terminal",
        "test_damaged_data_is_listed_refused_raised_and_recomputed",
        "test_metadata_of_the_wrong_shape_is_one_line_for_every_reader",
        "test_sigterm_is_exit_143_one_line_and_keeps_every_finished_scene",
    ),
    "test_initialised.py": (
        "test_a_rough_film_at_rest_has_no_cavity_and_repeats_exactly_in_another_process",
    ),
    "test_inputs.py": (
        "test_cli_bad_input_exits_2_without_traceback",
        "test_cli_failed_scene_exits_1_with_reason",
        "test_cli_output_into_a_closed_pipe_has_no_traceback",
        "test_cli_run_json_contract",
    ),
    "test_master.py": (
        "test_master_curve_matches_direct_solves",
    ),
    "test_piezoviscous_film.py": (
        "test_compression_energy_is_part_of_the_balance",
        "test_energy_closure_falls_with_the_tolerance",
        "test_rigid_barus_approach_agrees_with_a_coupled_phase_from_the_start",
        "test_whole_collisions_converge_under_refinement",
    ),
    "test_pipeline.py": (
        "test_a_beta_axis_sweep_end_to_end_draws_the_piezoviscous_figures",
        "test_a_crashing_worker_is_stored_as_an_error_and_the_sweep_goes_on",
        "test_a_store_with_pi_and_beta_axes_gets_both_figure_families",
        "test_a_three_axis_store_end_to_end",
        "test_critical_stokes_is_interpolated_between_grid_points",
        "test_existing_scheduler_runner_matches_serial",
        "test_extending_the_grid_computes_only_new_scenes",
        "test_figures_are_redrawn_only_when_the_store_changes",
        "test_figures_render_from_a_synthetic_store_with_reproducible_bytes",
        "test_kill_9_loses_nothing_and_recomputes_nothing",
        "test_real_solver_end_to_end_and_identical_across_runners",
    ),
    "test_scene_plots.py": (
        "test_cli_run_plot",
        "test_cli_scene_plot_and_paper_figures_bad_accuracy",
        "test_paper_figures_writes_figures_2_to_11",
        "test_plot_scene_writes_reproducible_files",
    ),
    "test_signals.py": (
        "test_sigterm_inside_the_compiled_solve_of_a_serial_sweep_stores_nothing",
    ),
    "test_startup.py": (
        "test_a_collision_is_the_same_compiled_or_loaded_and_whatever_was_compiled_before",
        "test_python_calls_only_the_compiled_entries",
        "test_a_sweep_with_nothing_to_do_loads_neither_dask_nor_the_solver",
        "test_figures_stamp_skips_reading_an_unchanged_store",
        "test_sticking_threshold_separates_sticking_from_rebounding",
    ),
    "test_sweep_fast_path.py": (
        "test_fast_path_sweep",
    ),
    "test_wet_restitution.py": (
        "test_x_ref_is_consistent_with_the_rigid_approach",
    ),
}


def pytest_collection_modifyitems(config, items):
    for item in items:
        path, _, name = item.nodeid.partition("::")
        if name.partition("[")[0] in SLOW.get(path.rpartition("/")[2], ()):
            item.add_marker(pytest.mark.slow)
