"""Breaks the suite must catch: each a mistake a domain expert could make (a sign, a missing
term, a wrong unit conversion, an off-by-one), written as edits of the source, and the tests
that must fail when it is made. ``tests/breaks/run.py`` applies each in a scratch copy of the
tree, runs its tests, and reports caught or missed (msg_docs/testing.md).

A new law, kernel term or sensor operation comes with its breaks here."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Break:
    """``edits``: (file, text, replacement), each text found exactly once in its file;
    ``tests``: pytest node ids that must fail with the edits made."""

    name: str
    edits: tuple[tuple[str, str, str], ...]
    tests: tuple[str, ...]


def one(name: str, file: str, text: str, replacement: str, *tests: str) -> Break:
    return Break(name, ((file, text, replacement),), tuple(tests))


CORE, CONTROL, SESSION, CLI = "drill_sim/core/", "drill_sim/control/", "drill_sim/session/", \
    "drill_sim/cli/"
T_TOP_DRIVE = "tests/core/test_top_drive.py"
T_DIST = "tests/core/test_distributed.py"
T_DIST_TD = "tests/core/test_distributed_top_drive.py"
T_DAMP = "tests/core/test_distributed_damping.py"
T_MODES = "tests/core/test_string_modes.py"
T_SECTIONS = "tests/core/test_string_sections.py"
T_WELL = "tests/core/test_well.py"
T_LAWS = "tests/control/test_control_laws.py"
T_SUP = "tests/control/test_control_supervisor.py"
T_EVAL = "tests/control/test_control_evaluation.py"
T_REG = "tests/control/test_z_torque_saturation_regulator.py"
T_SESSION = "tests/session/test_rig_session.py"
T_SCENARIO = "tests/session/test_scenario_on_the_clock.py"
T_VEC_TORQUE = "tests/gym/test_vector_env.py::test_each_rig_equals_a_rig_env_in_torque_mode"
T_MAP = "tests/study/test_map.py"

BREAKS: tuple[Break, ...] = (
    # ---- the top drive ----------------------------------------------------------------
    one("drive PI without its integral (K_i written as 0)", CORE + "simulator.py",
        "p[kn.P_KP], p[kn.P_KI] = d.rate, d.lag, d.kp, d.ki",
        "p[kn.P_KP], p[kn.P_KI] = d.rate, d.lag, d.kp, 0.0",
        f"{T_TOP_DRIVE}::test_speed_mode_holds_the_set_point_while_drilling",
        f"{T_DIST_TD}::test_speed_mode_holds_the_set_point_in_stick_slip",
        "tests/cli/test_cli_top_drive.py::"
        "test_speed_mode_holds_the_set_point_and_writes_the_drive_columns"),
    one("drive inertia counted with the BHA's (j = (J_TD + I)/I)", CORE + "top_drive.py",
        "j=self.top_drive_inertia_kg_m2 / bha_inertia_kg_m2",
        "j=(self.top_drive_inertia_kg_m2 + bha_inertia_kg_m2) / bha_inertia_kg_m2",
        "tests/cli/test_cli_top_drive.py::"
        "test_torque_mode_off_bottom_accelerates_under_the_command",
        T_TOP_DRIVE + "::test_motor_torque_step_accelerates_both_inertias_and_rings_at_the"
        "_two_inertia_mode"),
    # ---- the distributed string's SI conversion ---------------------------------------
    one("steel density x1.5 in the wave lines", CORE + "distributed.py",
        "            rho = sec.steel_density_kg_m3 or steel_density_kg_m3\n",
        "            rho = 1.5 * (sec.steel_density_kg_m3 or steel_density_kg_m3)\n",
        f"{T_DIST}::test_natural_frequencies_off_bottom", f"{T_DIST}::test_wave_travel_and"
        "_section_change", f"{T_DIST_TD}::test_free_string_rings_at_the_roots_with_the_drive"
        "_inertia_on_top", f"{T_DIST_TD}::test_rig_in_torque_mode_spins_the_whole_string_up"),
    one("axial damping x3 in the SI conversion", CORE + "distributed.py",
        "dash.append(per_length * sec.length_m / k / imp_scale",
        "dash.append((3.0 if damp == 'axial_damping' else 1.0) * per_length"
        " * sec.length_m / k / imp_scale",
        f"{T_DAMP}::test_free_modes_decay_as_the_continuously_damped_pipe"),
    # ---- the pipe's damping and the string's modes ----------------------------------------
    one("Kelvin-Voigt's stiffness G (1 + eta s) taken as G (1 + eta s / 2)",
        CORE + "distributed.py", "                q2 = 1.0 + eta * s\n",
        "                q2 = 1.0 + 0.5 * eta * s\n",
        f"{T_MODES}::test_modes_are_the_exact_roots_of_the_damped_pipe"),
    one("the retardation time read in ms, not s", CORE + "distributed.py",
        "            e = getattr(sec, retard) / ts\n",
        "            e = 1e-3 * getattr(sec, retard) / ts\n",
        f"{T_MODES}::test_modes_are_the_exact_roots_of_the_damped_pipe",
        f"{T_MODES}::test_shipped_presets_damp_every_mode_up_to_the_fifth"),
    one("the drive's PI left out of the modes' top boundary", CORE + "stability_distributed.py",
        "        k = k + drive.kp * s + drive.ki\n", "        k = k + 0.0 * s\n",
        f"{T_MODES}::test_modes_are_the_exact_roots_of_the_damped_pipe"),
    one("no low-pass on the passages: the station-node modes ring on", CORE + "distributed.py",
        "PASSAGE_SHARE = 0.2\n", "PASSAGE_SHARE = 0.0\n",
        f"{T_MODES}::test_no_mode_of_the_simulated_string_is_left_undamped"),
    one("the relative dashpots' dissipation not booked", CORE + "distributed_kernel.py",
        "            power += rel[j] * (om - speed[j + 1]) ** 2\n",
        "            power += 0.0 * rel[j] * (om - speed[j + 1]) ** 2\n",
        f"{T_DIST}::test_energy_balance_in_stick_slip"),
    one("the low-pass's state not kept from step to step", CORE + "distributed_kernel.py",
        "            state[0, j], state[1, j] = new_state[0, j], new_state[1, j]\n",
        "            state[0, j], state[1, j] = state[0, j], state[1, j]\n",
        f"{T_MODES}::test_simulation_rings_at_its_modes_close_to_the_exact_pipe"),
    one("a section's own modulus ignored by the wave lines", CORE + "distributed.py",
        "            modulus = getattr(sec, modulus_name) or default_modulus\n",
        "            modulus = default_modulus\n",
        f"{T_SECTIONS}::test_modes_of_a_tapered_string_are_its_transfer_matrices_in_si"),
    one("the pipe's stiffness from the string's modulus, not each section's",
        CORE + "string_geometry.py",
        "            c = 1.0 / sum(x.length_m / (self.shear_modulus(x) * x.polar_moment_m4)",
        "            c = 1.0 / sum(x.length_m / (self.shear_modulus_pa * x.polar_moment_m4)",
        f"{T_SECTIONS}::test_lumped_figures_of_a_tapered_string_are_the_closed_forms"),
    # ---- the well: survey, wall force, friction along the string ---------------------------
    one("W_s not projected on the hole's axis (the whole buoyed weight)", CORE + "well.py",
        "            total += 0.5 * (b - a) * float(np.sum(wq * t[:, 2]))\n",
        "            total += 0.5 * (b - a) * float(np.sum(wq))\n",
        f"{T_WELL}::test_submerged_weight_is_the_weight_along_the_holes_axis"),
    one("the bend's tension term on the weight's side", CORE + "well.py",
        "    return float(np.linalg.norm(tension_n * k + weight_n_m * (g - (g @ t) * t)))\n",
        "    return float(np.linalg.norm(-tension_n * k + weight_n_m * (g - (g @ t) * t)))\n",
        f"{T_WELL}::test_wall_force_is_the_soft_strings"),
    one("the wall's force counted per station, not per part", CORE + "distributed.py",
        "                held = sec.wall_n_m[j] * sec.length_m / k / sc.force_n"
        "      # n L_part [F*]\n",
        "                held = sec.wall_n_m[j] * sec.length_m / sc.force_n\n",
        f"{T_WELL}::test_break_off_torque_of_a_slant_well_is_the_closed_form"),
    one("a station at rest held to the sliding friction, not the static", CORE
        + "distributed_kernel.py",
        "            if rn <= (cap_s if stuck[j - 1] else cap_d):\n",
        "            if rn <= cap_d:\n",
        f"{T_WELL}::test_static_above_sliding_friction_breaks_off_from_the_top"),
    one("the wall's contacts coupled without the relative dashpots", CORE
        + "distributed_simulator.py",
        "        a -= np.diag(rel[1:-1], 1) + np.diag(rel[1:-1], -1)\n",
        "        a -= 0.0 * np.diag(rel[1:-1], 1)\n",
        f"{T_WELL}::test_every_rubbing_station_obeys_coulombs_law_at_every_step"),
    one("a contact that breaks loose keeps the static threshold for the step", CORE
        + "distributed_kernel.py",
        "                stuck[j - 1] = 0                     "
        "# broken loose: it slides this step\n",
        "",
        f"{T_WELL}::test_every_rubbing_station_obeys_coulombs_law_at_every_step"),
    one("the wall's dissipation not booked", CORE + "distributed_kernel.py",
        "            wall_t += sc[SC_FORCE, k] * om          # the wall's torque times the speed\n",
        "            wall_t += 0.0 * sc[SC_FORCE, k] * om\n",
        f"{T_WELL}::test_energy_balance_includes_the_walls_friction"),
    one("the rigid BHA does not rub", CORE + "distributed.py",
        "    if force <= 0.0:\n        return None\n",
        "    if True:\n        return None\n",
        f"{T_WELL}::test_break_off_torque_of_a_slant_well_is_the_closed_form"),
    one("the BHA rubs at its largest radius", CORE + "distributed.py",
        "            moment += held * 0.5 * part.od_m\n",
        "            moment += held * 0.5 * max(x.od_m for x in geometry.parts() if x.bha)\n",
        f"{T_WELL}::test_the_bhas_contact_is_its_sections_wall_force_at_their_radii"),
    one("the BHA at rest held only by the sliding friction", CORE + "distributed_kernel.py",
        "(cap_s if held and not loose else cap_d)", "cap_d",
        f"{T_WELL}::test_static_above_sliding_friction_breaks_off_from_the_top"),
    one("the BHA's contact solved once, apart from the bit's laws", CORE
        + "distributed_kernel.py",
        "    for _ in range(WALL_SWEEPS):\n        regime_new, w, t, g, v_new, om_new, event",
        "    for _ in range(1):\n        regime_new, w, t, g, v_new, om_new, event",
        f"{T_WELL}::test_the_rubbing_bha_obeys_coulombs_law_at_every_step"),
    one("the absorbing top matched to twice the pipe's impedance", CORE
        + "distributed_kernel.py",
        "            om_td_new = (level - tb_in[0]) / (2.0 * z_top)     # by the step's end",
        "            om_td_new = (level - tb_in[0]) / z_top",
        "tests/core/test_distributed.py::test_a_top_that_absorbs_reflects_nothing"),
    one("the wall's work on the BHA not booked", CORE + "distributed_kernel.py",
        "            wall_r += hs * ft_w * om_bar ",
        "            wall_r += 0.0 * ft_w * om_bar ",
        f"{T_WELL}::test_energy_balance_includes_the_walls_friction"),
    # ---- sensors ------------------------------------------------------------------------
    one("severity divided by the mid-range, not the mean", CORE + "sensors.py",
        "mean = win[W_SUM] / win[W_N] if win[W_N] > 0 else w",
        "mean = 0.5 * (win[W_MAX] + win[W_MIN]) if win[W_N] > 0 else w",
        "tests/core/test_sensors.py::"
        "test_stick_slip_severity_divides_by_the_mean_not_the_mid_range"),
    # ---- laws and supervisor -------------------------------------------------------------
    one("a gap in the stamps caught up on the new reading, not interpolated",
        CONTROL + "sampled_loop.py", "            f = k / periods\n", "            f = 1.0\n",
        "tests/control/test_sampled_loop.py"),
    one("a tick seen again stepped again", CONTROL + "sampled_loop.py",
        "if last is not None and m.time_s == last.time_s:", "if False:",
        "tests/control/test_sampled_loop.py"),
    one("PI without conditional integration (integral only clamped)", CONTROL + "laws.py",
        "        if p + q > self.torque_max_nm and error_rad_s > 0.0:\n"
        "            q = max(self.q_nm, self.torque_max_nm - p)\n"
        "        elif p + q < self.torque_min_nm and error_rad_s < 0.0:\n"
        "            q = min(self.q_nm, self.torque_min_nm - p)\n", "",
        f"{T_LAWS}::test_output_leaves_the_limit_as_soon_as_the_error_changes_sign",
        f"{T_SUP}::test_saturation_and_windup_are_counted"),
    one("a new law starts cold (no bumpless take-over)", CONTROL + "supervisor.py",
        "        self.law = new\n        self._started = False",
        "        self.law = new\n        self._started = True",
        f"{T_SUP}::test_a_new_law_or_new_gains_continue_from_the_last_output"),
    # ---- the offline loop, maps ----------------------------------------------------------
    one("the loop's series stamped 50 ms late", CONTROL + "closed_loop.py",
        'series["time_s"][k] = s.time_s', 'series["time_s"][k] = s.time_s + 0.05',
        f"{T_EVAL}::test_series_are_sampled_at_h"),
    one("a groups map drops beta from each point", CLI + "map_grid.py",
        'lam=v["lambda"], beta=v["beta"])', 'lam=v["lambda"])',
        f"{T_MAP}::test_groups_mode_sweeps_any_two_quantities"),
    one("the map's figure hard-wired to the stick fraction", CLI + "map.py",
        "column = next(c for c in METRICS if c.name == args.metric)",
        'column = next(c for c in METRICS if c.name == "stick_fraction")',
        f"{T_MAP}::test_plot_with_log_axes_and_another_metric"),
    # ---- the session ---------------------------------------------------------------------
    Break("scenario events applied once per advance, not per tick", (
        (SESSION + "rig_session.py",
         "                for _ in range(ticks):\n                    self.player.at_tick()\n"
         "                    self.rig.advance_steps(self._steps_per_tick)",
         "                self.player.at_tick()\n"
         "                self.rig.advance_steps(ticks * self._steps_per_tick)"),
        (SESSION + "rig_session.py", "        if self.player is None or ticks == 1:",
         "        if True:")),
        (f"{T_SCENARIO}::test_the_wall_clock_grouping_of_ticks_changes_nothing",)),
    one("the session's initial hook load adds the WOB instead of subtracting it",
        SESSION + "rules.py",
        'hook = rig.params.submerged_weight_n - p["initial_weight_on_bit_n"]',
        'hook = rig.params.submerged_weight_n + 0.1 * p["initial_weight_on_bit_n"]',
        "tests/session/test_session_top_drive.py"),
    one("a sample's stamp split at microseconds, not seconds", SESSION + "rig_messages.py",
        "sec, nsec = divmod(stamp_ns, 1_000_000_000)", "sec, nsec = divmod(stamp_ns, 1_000_000)",
        f"{T_SESSION}::test_measured_on_sample_sends_a_measured_topic_only_when_fresh"),
    one("the re-run truncates a stamp's step instead of rounding it", SESSION + "resim.py",
        "step = round((sim_time_s - self.session.offset_s) / self.rig.dt_s)",
        "step = int((sim_time_s - self.session.offset_s) / self.rig.dt_s)",
        f"{T_SESSION}::test_a_recorded_session_resimulates_bit_for_bit"),
    one("lockstep takes a later stamp as the answer", SESSION + "lockstep.py",
        "if stamp_ns == self.stamp_ns and topic in self.missing:",
        "if stamp_ns >= self.stamp_ns and topic in self.missing:",
        f"{T_SESSION}::test_lockstep_holds_the_tick_until_every_topic_answers_its_stamp"),
    one("a command's frame is not checked", SESSION + "rules.py",
        "    if frame_id not in COMMAND_FRAMES:", "    if False:",
        f"{T_SESSION}::test_a_refused_command_leaves_the_rig_untouched"),
    one("no in-flight grace after a drive-mode change", SESSION + "session_commands.py",
        "IN_FLIGHT_S = 0.5", "IN_FLIGHT_S = 0.0",
        f"{T_SESSION}::test_a_torque_command_needs_torque_mode_and_one_in_flight_is_dropped"),
    one("a reset restarts the session's clock", SESSION + "rig_session.py",
        "        self.offset_s = offset\n", "        self.offset_s = 0.0\n",
        f"{T_SESSION}::test_reset_starts_again_and_simulated_time_goes_on"),
    one("the start's perturbation ignored", SESSION + "rules.py",
        'perturbation=p.get("initial_perturbation", 0.0)', "perturbation=0.0",
        "tests/cli/test_cli_control.py::"
        "test_the_start_perturbation_is_one_option_and_an_offline_run_writes_an_exact_bag"),
    one("the offline loop makes a scenario's change a tick early", CONTROL + "closed_loop.py",
        "due(self._changes[0][0], k * self.h)", "due(self._changes[0][0], (k + 1) * self.h)",
        "tests/control/test_closed_loop_session.py::"
        "test_a_scenarios_parameter_change_lands_on_its_tick_offline_and_replays"),
    one("a scenario's controller switch asked a tick late", SESSION + "scenario_player.py",
        'due(switch.on_at_s, t + 1.0 / session.p["rate_hz"])', "due(switch.on_at_s, t)",
        f"{T_SCENARIO}::test_each_event_lands_on_the_tick_of_its_time"),
    one("MSE with the bit's circumference instead of its area", CONTROL + "evaluation.py",
        "    area = math.pi * preset.rig.bit_radius_m ** 2\n    drilled_m",
        "    area = 2.0 * math.pi * preset.rig.bit_radius_m\n    drilled_m",
        f"{T_EVAL}::test_mse_of_steady_drilling_is_teale_on_the_steady_state"),
    # ---- the kernel's laws ------------------------------------------------------------
    one("the stick law without the wear-flat friction", CORE + "bit_rock.py",
        "        return nd + beta_lam\n    return nd", "        return nd\n    return nd",
        "tests/core/test_validation.py::"
        "test_a_stuck_bit_breaks_free_when_the_string_torque_reaches_the_stick_law"),
    one("the contact law's g = 1 branch without the wear-flat force", CORE + "bit_rock.py",
        "v1 = v + hpsi * (w0 - nd - lam)", "v1 = v + hpsi * (w0 - nd)",
        "tests/core/test_validation.py::test_exact_steady_start_stays_on_the_trivial_solution",
        "tests/core/test_validation.py::test_averaged_invariants_in_stationary_stick_slip"),
    one("the drive's PI with its proportional gain halved", CORE + "kernel.py",
        "        half = 0.5 * kp\n", "        half = 0.25 * kp\n",
        f"{T_TOP_DRIVE}::test_speed_mode_holds_the_set_point_while_drilling",
        "tests/core/test_top_drive.py"),
    one("the blades' sweep skips the first node it passes (off by one)", CORE + "bit_rock.py",
        "    k_first = k_last + 1\n", "    k_first = k_last + 2\n",
        "tests/core/test_validation.py"),
    one("the groove cut at the end-of-step height, not where the blade passed",
        CORE + "bit_rock.py", "    return u + frac * (u_new - u)", "    return u_new",
        "tests/core/test_validation.py"),
    one("torque mode applies the command without its rate and torque limits", CORE + "kernel.py",
        "        r = min(max(t_cmd, lo), hi)\n", "        r = t_cmd\n",
        f"{T_TOP_DRIVE}::test_saturated_and_rate_limited_commands_show_the_limits"),
    # ---- the wire, bags, metrics --------------------------------------------------------
    one("stamped vectors written torque first", "drill_sim/wire/cdr.py",
        "values.pack_into(buf, at_values, *six)",
        "values.pack_into(buf, at_values, *six[3:], *six[:3])",
        "tests/wire/test_cdr.py::test_stamped_vectors_match_rclpy"),
    one("the SSI over the mean, not twice the mean", CORE + "stick_slip.py",
        "(speed_max - speed_min) / (2.0 * speed_mean)", "(speed_max - speed_min) / speed_mean",
        "tests/core/test_validation.py::test_ssi_is_the_spread_over_twice_the_mean_bit_speed",
        "tests/core/test_stick_slip.py"),
    one("the model's SSI from the window's mean and maximum, not its spread", CORE + "metrics.py",
        "ssi=severity_index(acc[kn.A_OMEGA_MAX], acc[kn.A_OMEGA_MIN], mean_omega)",
        "ssi=severity_index(acc[kn.A_OMEGA_MAX], mean_omega, mean_omega)",
        "tests/core/test_validation.py::test_ssi_is_the_spread_over_twice_the_mean_bit_speed"),
    one("a bit off bottom counted as stuck", CORE + "stick_slip.py",
        "return (bit_speed == 0.0) & (wob > 0.0)", "return (bit_speed == 0.0) & (wob >= 0.0)",
        "tests/core/test_stick_slip.py"),
    one("a bag's metadata counts one message less a file", "drill_sim/bag/metadata.py",
        '"message_count": count}', '"message_count": count - 1}',
        "tests/bag/test_bag.py::test_metadata_yaml_counts_every_message_per_file_and_topic"),
    # ---- sensors --------------------------------------------------------------------------
    one("quantisation truncates instead of rounding to the nearest step", CORE + "sensors.py",
        "                v = np.round(v / q) * q", "                v = np.floor(v / q) * q",
        "tests/core/test_sensors.py::test_quantisation_rounds_to_the_nearest_step"),
    one("a sensor's bias subtracted", CORE + "sensors.py",
        "v = st[c, S_Y] + par[c, P_BIAS]", "v = st[c, S_Y] - par[c, P_BIAS]",
        "tests/core/test_sensors.py"),
    # ---- control filters -------------------------------------------------------------------
    one("a first-order section's decay linearised (1 - h/tau)", CONTROL + "filters.py",
        "self.decay = math.exp(-h_s / self.tau_s) if self.tau_s > 0.0 else 0.0",
        "self.decay = max(0.0, 1.0 - h_s / self.tau_s) if self.tau_s > 0.0 else 0.0",
        "tests/control/test_control_filters.py::"
        "test_held_lag_is_the_exact_exponential_of_a_held_step"),
    # ---- SI at the boundary, the session's rules, pacing, Z-Torque --------------------------
    one("the rig's speed command scaled by 1/t* instead of t*", CORE + "rig.py",
        "        return speed_rad_s * self.scales.time_s\n",
        "        return speed_rad_s / self.scales.time_s\n",
        "tests/core/test_rig.py::test_si_steady_start_reads_the_steady_state"),
    one("W0 from the hook load with the wrong sign", CORE + "rig.py",
        "return (self.params.submerged_weight_n - hook_load_n) / self.scales.force_n",
        "return (hook_load_n - self.params.submerged_weight_n) / self.scales.force_n",
        "tests/core/test_rig.py"),
    one("a recorded parameter change not redone by the re-run", SESSION + "resim.py",
        "            new.update({k: rules.parse_value(v) for k, v in event[\"values\"].items()})\n",
        "",
        f"{T_SESSION}::test_a_recorded_session_resimulates_bit_for_bit"),
    one("a stall of any length published tick by tick (no catch-up limit)",
        SESSION + "pacing.py", "CATCH_UP_TICKS = 5\n", "CATCH_UP_TICKS = 10**9\n",
        "tests/session/test_node_policy.py::"
        "test_a_short_stall_samples_each_tick_and_a_long_one_all_at_once"),
    one("a tick of one step more than its share", SESSION + "rules.py",
        '    return tick_s / steps_per_tick(tick_s, p["dt_s"])',
        '    return tick_s / (steps_per_tick(tick_s, p["dt_s"]) + 1)',
        "tests/session/test_node_policy.py::test_the_step_divides_the_tick"),
    one("Z-Torque's torque feedback with the wrong sign", CONTROL + "z_torque.py",
        "- self.alpha_in_use * t_tilde / self.impedance_nm_s_rad)",
        "+ self.alpha_in_use * t_tilde / self.impedance_nm_s_rad)",
        "tests/control/test_z_torque_alignment.py"),
    one("the bumpless start leaves the law's first output off the current torque",
        CONTROL + "laws.py", "        q = output_nm - gain * error_rad_s\n",
        "        q = output_nm - self.kp_nm_s_rad * error_rad_s\n",
        f"{T_LAWS}::test_bumpless_start_first_output_is_the_current_torque"),
    one("SoftSpeed's inertia compensation with the wrong sign in the closed-loop roots",
        CONTROL + "impedance.py", "(c - law.compensated_inertia_kg_m2 * d)",
        "(c + law.compensated_inertia_kg_m2 * d)",
        "tests/control/test_closed_loop_roots.py"),
    one("Z-Torque's roots read this sample's command as the measured motor torque",
        CONTROL + "impedance.py", "loop = 1.0 - b * zi / lag", "loop = 1.0 - b / lag",
        "tests/control/test_closed_loop_roots.py"),
    one("the spectral peak refined away from its neighbour", CONTROL + "tuning.py",
        "0.5 * (a - c) / curvature", "0.5 * (c - a) / curvature",
        "tests/control/test_control_filters.py::"
        "test_a_clean_tone_between_bins_is_found_to_a_thousandth_of_a_bin"),
    one("the steady start's bit speed not perturbed", CORE + "simulator.py",
        "self._x[kn.X_OMEGA] = st.omega0 * (1.0 + perturbation)",
        "self._x[kn.X_OMEGA] = st.omega0",
        "tests/core/test_rig.py::test_a_perturbed_steady_start_speeds_only_the_bit"),
    one("the held block lets the string's top follow the hook's force", CORE +
        "distributed_kernel.py", "            v_top = v_block\n",
        "            v_top = (w0 - ab_in[0]) / az[0]\n",
        "tests/core/test_hook_position.py::test_held_block_drills_off_the_strings_stretch",
        "tests/core/test_hook_position.py::test_lowered_block_sets_the_drill_rate"),
    one("the block's speed taken positive up", CORE + "rig.py",
        "sim.set_hook(mode == \"position\", speed / self.scales.velocity_m_s)",
        "sim.set_hook(mode == \"position\", -speed / self.scales.velocity_m_s)",
        "tests/core/test_hook_position.py::test_lowered_block_sets_the_drill_rate"),
    one("the hook load shown is the command in position mode too", CORE + "rig.py",
        "            hook_load_n=self._hook_load_n if self.hook_mode == \"force\"\n",
        "            hook_load_n=self._hook_load_n if True\n",
        "tests/core/test_hook_position.py::test_held_block_drills_off_the_strings_stretch"),
    one("a formation's specific energy taken inverted", CORE + "rig.py",
        'rock["intrinsic_specific_energy_pa"] / p.intrinsic_specific_energy_pa,',
        'p.intrinsic_specific_energy_pa / rock["intrinsic_specific_energy_pa"],',
        "tests/core/test_formations.py::test_the_bit_cuts_each_layers_rock_from_the_step_it_enters",
        "tests/core/test_formations.py::test_a_steady_start_in_a_layer_drills_its_rock"),
    one("a formation's contact stress not reaching the wear flats", CORE + "rig.py",
        'p.bit_radius_m * p.wear_flat_length_m * rock["contact_stress_pa"]',
        'p.bit_radius_m * p.wear_flat_length_m * p.contact_stress_pa',
        "tests/core/test_formations.py::test_the_bit_cuts_each_layers_rock_from_the_step_it_enters"),
    one("a formation's friction coefficient not reaching the torque", CORE + "rig.py",
        'rock["friction_coefficient"] * p.wear_flat_orientation * p.cutting_inclination)',
        'p.friction_coefficient * p.wear_flat_orientation * p.cutting_inclination)',
        "tests/core/test_formations.py::test_the_bit_cuts_each_layers_rock_from_the_step_it_enters",
        "tests/core/test_formations.py::test_a_steady_start_in_a_layer_drills_its_rock"),
    one("a steady start in a harder layer at the softer rock's depth of cut", CORE +
        "simulator.py", "return replace(st, delta_n0=st.delta_n0 / cutting, v0=st.v0 / cutting)",
        "return st",
        "tests/core/test_formations.py::test_a_steady_start_in_a_layer_drills_its_rock"),
    one("a formation crossed forgets what the layers above it gave", CORE + "rig.py",
        "rock, crossed = dict(self.rock), self.formations[self.layer + 1:layer + 1]",
        "rock, crossed = self._params_rock(self.params), self.formations[layer:layer + 1]",
        "tests/core/test_formations.py::test_the_bit_cuts_each_layers_rock_from_the_step_it_enters",
        "tests/core/test_formations.py::test_a_run_time_change_holds_until_a_layer_gives_that_value"),
    one("a lumped session's bag without its formations", SESSION + "recorder.py",
        'if rig.geometry is not None and (rig.string_model == "distributed" or rig.formations)',
        'if rig.geometry is not None and rig.string_model == "distributed"',
        "tests/session/test_formations_session.py"),
    one("the environment shows the set-point a sample late", "drill_sim/gym/rig_env.py",
        "m.hook_load_n, float(loop.speed_set[min(loop.k, loop.n)])])",
        "m.hook_load_n, float(loop.speed_set[max(loop.k - 1, 0)])])",
        "tests/gym/test_rig_env.py::test_z_torque_as_a_policy_scores_as_drill_sim_control"),
    one("the environment shows the surface torque as the motor torque", "drill_sim/gym/rig_env.py",
        "return np.array([m.top_drive_speed_rad_s, m.motor_torque_nm, m.surface_torque_nm,",
        "return np.array([m.top_drive_speed_rad_s, m.surface_torque_nm, m.surface_torque_nm,",
        "tests/gym/test_rig_env.py::test_z_torque_as_a_policy_scores_as_drill_sim_control"),
    one("effort: the motor torque's RMS of the torque itself, not of its deviation",
        CORE + "effort.py",
        '"motor_torque_rms_nm": math.sqrt(self.m2 / self.n) if motor else None,',
        '"motor_torque_rms_nm": math.sqrt(self.m2 / self.n + self.mean**2) if motor else None,',
        "tests/core/test_effort.py::test_motor_figures_equal_the_closed_forms_of_a_sine"),
    one("effort: the torque rate without the time step", CORE + "effort.py",
        "rate = np.diff(torque)[step] / dt[step]", "rate = np.diff(torque)[step]",
        "tests/core/test_effort.py::test_motor_figures_equal_the_closed_forms_of_a_sine"),
    one("effort: settling counted from the first event, not the last", CORE + "effort.py",
        "return round((first + settled_from) * BLOCK_S + self.start_s - events[-1], 9)",
        "return round((first + settled_from) * BLOCK_S + self.start_s - events[0], 9)",
        "tests/core/test_effort.py::test_settling_time_is_the_definition_and_the_decay_of_an_envelope"),
    one("a recorder's gap counted one too many", "drill_sim/bag/losses.py",
        "self.gaps.append(Gap(topic, sequence - last[0] - 1, last[1], t_s))",
        "self.gaps.append(Gap(topic, sequence - last[0], last[1], t_s))",
        "tests/bag/test_losses.py::test_each_jump_is_the_messages_between_and_when",
        "tests/ros/test_record_replay.py::test_record_reports_exactly_the_messages_it_never_received"),
    one("command_owner first that cannot tell publishers apart (one GID read for all)",
        "drill_sim/ros/publisher_take.py",
        "                     bytes(info.publisher_gid.data))",
        "                     bytes(8))",
        "tests/ros/test_node_process.py::"
        "test_command_owner_first_takes_one_publishers_commands_and_names_the_refused"),
    one("lockstep: the drive's wait stays on the topic of the mode it started in",
        SESSION + "lockstep.py", "        if to is None or len(drive) != 1 or drive[0] == to:",
        "        if True:",
        "tests/session/test_lockstep_rule.py::"
        "test_the_drives_lockstep_topic_follows_its_mode_and_an_answered_tick_stays_answered",
        "tests/ros/test_controller_lockstep.py::"
        "test_a_managed_controller_disabled_in_lockstep_answers_with_its_set_point"),
    one("a managed controller, disabled in lockstep, stays silent", "drill_sim/ros/controller.py",
        "            elif self._rig_lockstep:\n                self._answer_disabled(",
        "            elif False:\n                self._answer_disabled(",
        "tests/ros/test_controller_lockstep.py::"
        "test_a_managed_controller_disabled_in_lockstep_answers_with_its_set_point"),
    one("vector environment: the hook load of the sample after the command's",
        "drill_sim/gym/vector_step.py", "        m[M_HOOK] = hook[i, j - 1]",
        "        m[M_HOOK] = hook[i, j]",
        T_VEC_TORQUE,
        "tests/gym/test_vector_env.py::test_each_rig_equals_a_rig_env_in_speed_mode"),
    one("vector environment: the torque-rate penalty of the action before clipping",
        "drill_sim/gym/vector_step.py",
        "            rate = (abs(held - held_before[i]) / weights[W_H] / 1e6) ** 2",
        "            rate = (abs(value - held_before[i]) / weights[W_H] / 1e6) ** 2",
        T_VEC_TORQUE),
    one("vector environment: the WOB as the last step's, not the sample's mean",
        "drill_sim/gym/vector_step.py", "        last[F_WOB, i] = (0.0 + sum_w * fn) / n",
        "        last[F_WOB, i] = x[i, kn.X_W] * fn",
        T_VEC_TORQUE),
    one("vector environment: a noisy profile's block of deviates not refilled",
        "drill_sim/gym/vector_env.py",
        "            self.envs[i].loop.session.sensors._refill()", "            pass",
        "tests/gym/test_vector_env.py::test_the_sensors_noise_continues_past_a_block"),
    one("vector environment: the distributed string's torsional waves of rig 0 for every rig",
        "drill_sim/gym/vector_step.py", "tbuf[i], tlp, tstate[i],", "tbuf[0], tlp, tstate[i],",
        T_VEC_TORQUE),
    one("a program running on after an import swallowed the signal's exit",
        "drill_sim/entry_points.py", "    if _SIGNALLED:", "    if False:",
        "tests/cli/test_entry_points.py::test_a_signal_whose_exit_an_import_swallowed_still_"
        "stops_the_program"),
    one("a stamped topic matched without reading past the last stamp",
        "drill_sim/bag/stamped_series.py", "self._ns[-1] <= last):", "self._ns[-1] < last):",
        "tests/bag/test_stamped_series.py::test_a_shared_stamp_split_across_chunks_at_the_end_"
        "of_a_read_is_matched"),
    one("a session bag read once without its motor torque in the effort",
        "drill_sim/bag/session_events.py",
        "            stats.add((ns - origin) / 1e9, named[\"bit_speed_rad_s\"], torque,",
        "            stats.add((ns - origin) / 1e9, named[\"bit_speed_rad_s\"], None,",
        "tests/bag/test_bag_compare.py"),
    one("the distributed string's Z-Torque at the lumped rule's α 0.5",
        f"{CONTROL}reference.py", "DISTRIBUTED_Z_TORQUE_ALPHA = 0.3 ",
        "DISTRIBUTED_Z_TORQUE_ALPHA = 0.5 ",
        f"{T_EVAL}::test_on_long_z_torque_as_commissioned_cures_100_rpm_160_kn_"
        "through_the_rigs_sensors"),
    one("the distributed string's Z-Torque without its saturation regulator",
        f"{CONTROL}reference.py", "        gains.update(DISTRIBUTED_Z_TORQUE_BACKOFF)\n", "",
        f"{T_EVAL}::test_on_field_a_z_torque_cures_100_rpm_250_kn_within_the_motor_through_"
        "the_rigs_sensors"),
    one("Z-Torque's saturation regulator backing α off at the rate it climbs back",
        f"{CONTROL}z_torque.py", "step * (1.0 - self.saturation_target)",
        "step * self.saturation_target",
        f"{T_REG}::test_alpha_backs_off_on_a_limit_and_climbs_back_off_it_at_the_documented_rates",
        f"{T_EVAL}::test_on_field_a_z_torque_cures_100_rpm_250_kn_within_the_motor_through_"
        "the_rigs_sensors"),
    one("Z-Torque's reset and bumpless start keeping the regulator's backed-off α",
        f"{CONTROL}z_torque.py",
        "        self.alpha_scale = 1.0                 # taking over: the full match until a "
        "limit\n", "",
        "tests/control/test_law_state.py::test_a_reset_forgets_the_history",
        f"{T_REG}::test_taking_over_restores_the_full_alpha"),
    one("the distributed string's Z-Torque keeping the noise rule's low torque low-pass",
        f"{CONTROL}reference.py",
        'k not in SIGNAL_GAINS and k != "torque_lowpass_hz"}',
        'k not in SIGNAL_GAINS}',
        f"{T_EVAL}::test_on_long_z_torque_as_commissioned_cures_100_rpm_160_kn_"
        "through_the_rigs_sensors"),
    one("the distributed string's Z-Torque on a drive's signals with the exact signals' low-pass",
        f"{CONTROL}reference.py", "    if signals or noisy:          # a drive's signals",
        "    if not signals:               # a drive's signals",
        f"{T_EVAL}::test_on_base_z_torque_through_the_rigs_sensors_stays_off_its_limits"),
    one("the distributed string's Z-Torque on a noisy speed left uncapped",
        f"{CONTROL}reference.py", "    if signals or noisy:          # a drive's signals",
        "    if signals:                   # a drive's signals",
        "tests/control/test_reference_tuning.py::"
        "test_on_the_distributed_string_z_torque_is_capped_for_a_drives_signals"),
    one("a preset's commissioned gains left out of its reference gains",
        f"{CONTROL}reference.py", "        tuned.update(preset.commissioned(law))\n", "",
        "tests/control/test_reference_tuning.py::"
        "test_a_presets_commissioning_sets_its_gains_for_a_drives_signals_only",
        f"{T_EVAL}::test_on_long_z_torque_as_commissioned_cures_100_rpm_160_kn_"
        "through_the_rigs_sensors"),
)
