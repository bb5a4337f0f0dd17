//! The reference texts of `host-sim help` and of each command's `--help`, below the
//! options clap lists.

/// What `host-sim --help` says first.
pub const ABOUT_LONG: &str = "\
host-sim: simulate the built-in mechanisms of the structomat core, or mechanisms and
the Constantinesco converter described in run files (TOML)";

/// After the commands in `host-sim --help`: the scenarios, the examples, the exit
/// status.
pub const TOP: &str = "\
Scenarios: slider-crank, five-bar (mechanisms);
           ccc-s1, ccc-s2 (the Constantinesco torque converter, SPEC 3)
  Each ships as a run file, host-sim/scenarios/<name>.toml (embedded): copy one to
  start your own.
Examples: host-sim/mechanisms/*.toml (run files), host-sim/sweeps/*.toml (sweep
  files), host-sim/batches/*.batch (batch files), examples/design/*.toml (design
  files).

Exit status: 0 success, 1 run failure (step error, file error), 2 bad arguments or a
bad run file.

Each command's options and reference: host-sim help <COMMAND> (or <COMMAND> --help).";

/// After the options in `host-sim run --help`: the CSV columns, the converter's files
/// and the run files' keys.
pub const RUN: &str = "\
CSV columns (one row at t = 0, then one per written step):
  t                  time, s
  q{j} qd{j} qdd{j}  coordinate j (1-based), its rate and acceleration
  motor_torque{j}    applied torque (N·m) or force (N) of the drive on coordinate j
  then, for every group of the sequence and every joint of the group (kinetostatics):
  R{i}_{j}           revolute joint between bodies i and j (0 = ground): |reaction|, N
  N{i}_{j} M{i}_{j}  prismatic joint: |normal force|, N, and reaction moment, N·m
  drive_torque{j}    driving torque (force) the motion requires on coordinate j
  A repeated name gets a suffix _2, _3, ...

Converter scenarios (ccc-s1: free mode, h = 1e-4 s, t_end = 1 s; ccc-s2: h = 1e-4 s,
t_end = 1 s): a row at t = 0, every N-th step and the last state, columns
  t mode mode_code coords       time, s; mode name (free I0 I6 I8 jam A6 A8 A68 coast),
                                its code 0..8 in that order (coast: the shaft turning
                                with no lever, only with shaft_inertia > 0), the
                                independent coordinates
  q1 q2 qd1 qd2                 coordinates (rad) and speeds (rad/s); empty past the
                                mode's DOF (q2 in 1-DOF modes, all four in jam)
  theta{p} omega{p}             angle (rad, unwrapped) and speed (rad/s) of link p = 1..8
  shaft_speed shaft_angle       output shaft, rad/s and rad turned, CCW positive
  c6 c8                         torque each clutch transmits, N·m, + in drive direction
  motor_torque                  motor torque on the crank, N·m
  R_A R_B R_C R_E R_F R_D5 R_D7 R_G R_I R_H6 R_H8   |joint reaction|, N
  kinetic potential             energy now, J
  motor_work load_work impact_loss audit_residual   energy audit since t = 0, J
  With --out FILE, the mode changes go to FILE's stem + .events.csv (time, event,
  from, to, c6, c8, impact_loss, mismatch; the first row is the start event, except in
  free mode, which has no mode choice) and the coordinate switches to stem +
  .switches.csv (time, mode, from, to, conditioning_before, conditioning_after); with
  the CSV on stdout these two logs are not written.
  The summary gives the first breakaway, the events by kind, the coordinate switches,
  the energy audit and how the run ended; it is printed also when a step fails.
  ccc-s1 ending at the mechanism's singularity is its expected end: exit status 0.

Every run: h <= t_end (else exit status 2); when t_end is not a multiple of h, the last
  step is shortened to end on t_end; the CSV's last row is the last state, whatever
  --every. The files are written to a hidden temporary file in their folder and renamed
  when the run is over (a crash leaves no half file); the pictures of a failed run are
  not written; an output that names the run file is refused. Ctrl-C (SIGINT) or SIGTERM:
  the run finishes its row, completes its CSV and logs, prints its summary marked
  interrupted and exits with status 130 (a second signal ends it at once); in a batch
  or a sweep the runs under way stop so, the others are not started (end: not run),
  and it exits 130. A run that meets a singularity of the mechanism ends there, located
  inside the step, with exit status 0 (end: singularity). On a terminal a long run
  shows its progress on stderr.

Run files (TOML; the full reference with every key: host-sim/scenarios/README.md).
  SI units (m, kg, kg·m², s, N, N·m, rad/s); angles in degrees in keys ending in _deg,
  motor speeds in rpm in keys ending in _rpm. Unknown keys are errors; every value is
  checked before the first step; an error names the file, the line:column when the
  toml parser knows it, and the field, e.g.  my.toml: link \"coupler\".mass: must be >= 0
  A mechanism:
    name, description, gravity = [gx, gy] (m/s², default [0, -9.81])
    [[ground]]  name, at = [x, y]
    [[link]]    name, mass, inertia (about the COG), length (a bar: points start, end)
                or none (a block: point origin), points = { D = [x, y], ... } (link
                frame), cog = distance along the bar or [x, y] (default: the midpoint),
                angle_deg (the initial guess of the link's angle: picks the branch)
    [[joint]]   name, type = \"revolute\", points = [\"A\", \"crank.start\"]
                or type = \"prismatic\", slider = \"slider.origin\", guide = \"A\",
                guide_angle_deg, slider_angle_deg, offset (the guess along the guide, m)
                A point is a ground point's name or link.point (start, end, origin, a
                named point, or an index).
    [[driver]]  link, joint (the motor element: link about/along joint; coordinates
                q1, q2, ... in driver order), q0_deg (revolute) or q0 (prismatic, m),
                qd0, offset_deg, motor
    [[load]]    link, at = [x, y] (link frame), force = [fx, fy] (N), moment (N·m)
    The motion-transmission sequence is found by `host-sim analyze`'s search.
  The converter: [converter] a, f, h (pivots A, F and shaft H), [[converter.link]] x 8
    (length, mass, inertia), rocker_d, mass, mass_inertia, mass_at, shaft_inertia,
    drive = \"cw\"|\"ccw\", gravity, branch_c, branch_g, branch_i = \"left\"|\"right\",
    crank_deg, swing_deg, crank_speed, swing_speed, motor_offset (N·m added to a
    bench log's measured motor torque by replay, default 0); [converter.friction] (all 0 by
    default): viscous = { A, B, C, E, F, D5, D7, G, I } (N·m·s/rad on each joint's
    relative speed), coulomb = { ... } (dry friction, N·m), coulomb_eps (its
    regularization speed, rad/s, default 0.01), clutch_drag (N·m·s/rad, an overrunning
    clutch's slip)
  [run] h, t_end (s), every, f32, integrator = \"dp5\" (the fixed-step Dormand-Prince,
    step h; the default) or \"adaptive\" (the adaptive DP5(4) between output times h
    apart, with rtol, atol (default 1e-9 each) and h_max (default 10 h); mechanisms
    only: the twin steps with a fixed h); converter only: mode =
    \"clutch\"|\"free\", motor, load (T_r, N·m)
  motor = a torque in N·m, or { type = \"constant\", torque }, { type = \"asynchronous\",
    breakdown_rpm, breakdown_torque, rated_rpm, rated_torque, synchronous_rpm },
    { type = \"polynomial\", a, b, c } (T = a + b ω + c ω², ω in rad/s)";

/// After the options in `host-sim batch --help`: the batch file and the files written.
pub const BATCH: &str = "\
Batch files:
  FILE lists one run a line, written like the arguments of run, e.g.
    ccc-s2 --load 600 --motor 10 --t-end 0.3
  without --out (the batch names the files); '#' starts a comment, blank lines are
  skipped. Every line is checked before anything runs: a bad line is an error naming
  its line number (exit status 2).
  Files, for job k (0, 1, ... in line order, written with at least 3 digits):
  k-<scenario>.csv, and for the converter scenarios k-<scenario>.events.csv and
  .switches.csv: byte for byte what `host-sim run <line> --out k-<scenario>.csv` writes.
  batch.csv, one row per job in job order, columns
  job line scenario args file   job index, its line in FILE, the scenario, the
                                line's arguments, the job's CSV file name
  exit end                      the exit status the run alone gives; how it ended:
                                completed, singularity (at a singularity of the
                                mechanism: ccc-s1's expected end, or the diode's rods
                                and levers in line), failed (a step failed otherwise)
                                or error (setup, file)
  steps time rows               steps completed, time of the last state, s (empty when a
                                mechanism's step failed), CSV data rows
  first_breakaway events switches audit_residual
                                converter runs: first breakaway, s (empty if none),
                                events, coordinate switches, energy audit residual, J
  message                       the error of a run that did not complete
  Exit status: 0 when every run succeeded (exit status 0 alone), 1 otherwise.";

/// After the options in `host-sim sweep --help`: the sweep file and the files written.
pub const SWEEP: &str = "\
Sweep (host-sim sweep FILE --out-dir DIR): every combination of the axes' values of a
base run, N at a time; example: host-sim/sweeps/mass-motor.toml
  base = \"ccc-s2\"     a built-in scenario, or a run file (path relative to FILE)
  threads = N         runs at a time (default 2; --threads overrides it)
  [set]               fixed changes to the base: \"run.t_end\" = 0.3, ...
  [[axis]]            key = \"converter.mass\" (a dotted key of the run file; a number
                      picks an array element: \"converter.link.2.mass\"), label, and
                      values = [..] or from, to, steps (evenly spaced, ends included)
  [[heatmap]]         metric (a numeric column below), x, y (axis keys; default: the
                      first two numeric axes); default: first_breakaway
  Every variant is checked as a run file before anything runs (exit status 2 on a
  bad one, named by its number and axis values). Variants are numbered in grid order
  (the first axis outermost); the files do not depend on --threads.
  --out-dir DIR      where the files go (created if missing)
  --threads N        runs at a time, on N threads
  --progress STYLE   bar (redrawn in place), lines (one per tenth) or none; default:
    impact_loss, message  (empty where it does not apply);
  heatmap<n>-<metric>.svg and .png per [[heatmap]] (with -<k> per combination of the
  other axes' values). The summary gives the lowest and highest value of each
  heat-map's metric and the variant that gave it. A variant that fails is a row
  (end = singularity or failed, as in batch.csv), not a failure of the sweep: exit
  status 0 when the files are written.";

/// After the options in `host-sim design --help`: the design file and the files written.
pub const DESIGN: &str = "\
Design (host-sim design FILE --out-dir DIR): a search for the converter that meets the
constraints with the best objective; example: examples/design/s2-800.toml
  base = \"ccc-s2\"     a converter scenario, or a run file (path relative to FILE)
  [set]               fixed changes to the base, by dotted key (as a sweep's)
  [[free]]            key (a numeric dotted key), min, max, label: a free parameter
  [[point]]           load (T_r, N·m), motor (N·m; else the base's), horizon (s)
  [objective]         metric = \"mean_power\" (mean power to the load over the last
                      half of the horizon, maximised; the lowest over the points) or
                      \"first_breakaway\" (minimised)
  [constraints]       margin = δ (m, default 0.005): |DH| <= rod + lever - δ at every
                      step; no_jam, assembly (every 5° of the crank at the initial swing
                      angle), horizon (the twin reaches it): true by default
  [search]            population (16), generations (20), seed (1), weight F (0.7),
                      crossover CR (0.9): differential evolution, DE/rand/1/bin
  [front]             loads = [..]: one more search per load (the first point's motor
                      and horizon), each from the main search's best feasible
                      design, drawn as front.svg/.png; population, generations
                      (default: [search]'s)
  Constraints by Deb's rule: a feasible design beats every infeasible one; two
  infeasible ones compare by their total violation (designs.csv's v_* columns, each
  0..1). The search starts from the base's values when they are inside the bounds.
  Everything is checked before anything runs (exit status 2, the field named); the
  files do not depend on --threads.
  --out-dir DIR      where the files go (created if missing)
  --threads N        runs at a time, on N threads
  --no-winner        do not run the winner (its files and the check at h/2)
Files: best.toml (the winner as a run file at the first point), designs.csv (every
  design at every point: search, generation, member, the free values, how it ended,
  the margin, the jam, the objective, the violations), convergence.svg/.png, front.csv
  and front.svg/.png with [front], winner/ (run.csv, its logs, plots, run.gif) and
  the winner at h/2 in the summary.";

/// After the options in `host-sim replay --help`: the logs, the columns, the summary.
pub const REPLAY: &str = "\
The bench log (CSV, one sample a row, uniform from t = 0; other columns ignored):
  t             time, s
  motor_torque  the motor torque on the crank, N·m, CCW positive
  load_torque   the brake's set point T_r >= 0, N·m
  crank_counts  crank encoder, 4096 counts a turn: floor(q1 / (2π/4096)), q1 not wrapped
  shaft_counts  shaft encoder, 4096 counts a turn, positive in the drive direction, 0 at
                t = 0
  A missing column, a value that is not a finite number, a count that is not whole or
  past ±2^53, a first shaft count other than 0, a t that does not increase or is not
  uniform (a missing sample) is refused with its line and column named (exit status 2).

The twin steps at the log's sample period (h = the mean interval), each step under the
sample's motor torque and load (held over the step); --params gives the converter's
parameters, drive direction and initial state (its motor, load, h and t_end are not
used). The CSV's columns are run's for a converter (see host-sim help run) and
  crank_counts twin_crank_counts crank_residual   the log's count, the twin's crank
                angle by the encoder law (offset to the log's first count), measured -
                twin
  shaft_counts twin_shaft_counts shaft_residual   the same for the shaft's angle turned
                in the drive direction from 0
  with the event and switch logs next to the CSV (FILE's stem + .events.csv,
  .switches.csv).

The clutch log (CSV: t, event, from, to; the events and modes in host-sim's names, as
  the twin's event log): its events are paired in order with the twin's (the twin's
  start left out). The summary lists every pair with its time difference (twin -
  machine) and names the first pair that differs (the event, the mode before or
  after), and the events missing or extra at the end. A twin's `inputs` event (a mode
  change at a step's start, under the new sample) is the machine's event between the
  same modes.

--observer [nominal|identified]: the core's observer (an error-state Kalman filter on
  the crank's angle and speed) steps the twin and corrects it from the log's encoders
  after every step; the crank's count is then absolute (no offset). Its tuning is how
  far it trusts the twin's model: nominal (the default) for the drawing's parameters,
  identified for a run file that host-sim identify wrote (less process noise, the
  2-DOF modes corrected too); each follows the machine worse on the other's twin
  (README, \"The observer\"). The CSV gains
  crank_innovation crank_sigma   the crank's count measured - predicted, and the
                standard deviation of the angle's error after the update, counts
  shaft_innovation   the shaft's motion since the last mode change, measured - twin,
                counts
  crank_jump shaft_jump clutch_slip failed_catch load_bias twin_parted
                1 at a step that raised the diagnostic (twin_parted: the crank's
                residual past 16 counts for 10 steps in a row, at each step it lasts)
  and the summary the innovations' and residuals' RMS and largest (over the run and
  after its first 20 ms), the corrections' energy and each diagnostic's onsets.
  host-sim plot of that CSV draws encoders (measured and twin) and observer (the
  innovations, the residual after the update, the diagnostics raised over time).";

/// After the options in `host-sim identify --help`: what is fitted, how, the file.
pub const IDENTIFY: &str = "\
The bench log and the clutch log are replay's (host-sim help replay). Each trial
replays the log open-loop on the converter of --params with the --fit parameters set;
its residuals are, per sample, the twin's crank and shaft angle in counts (the encoder
law without its floor) less the middle of the count measured, and with --clutch-log,
per pair of events, the time difference in units of 0.05 ms (a pair that differs, or an
event missing: as 10 ms). Nelder-Mead (argmin) minimizes their sum of squares within
the bounds: a mass or an inertia within ±10 % of the base file's value, a friction
coefficient in [0, 1] (N·m·s/rad or N·m), converter.motor_offset in [-2, 2] N·m.

--fit keys: converter.link.K.mass, converter.link.K.inertia (K = 0..7, SPEC 3's
order), converter.mass, converter.mass_inertia, converter.friction.viscous.J,
converter.friction.coulomb.J (J one of A B C E F D5 D7 G I),
converter.friction.clutch_drag, converter.motor_offset. Stages are separated by ';'
(`a,b;c`: a and b searched first, c freed from their best); the default's six, then
the friction at F: from SPEC's machine, the seven at once settle in another valley on
some logs (the known machine's at 800 N·m and 10 N·m).

The file written is the base file with the identified values at their keys (and name,
description); its comments give each value ± its standard uncertainty from the
Gauss-Newton covariance s²(JᵀJ)⁻¹ at the optimum (J the residuals' Jacobian by central
differences, s² their variance), the bounds, and the replay's residuals and events.
replay --params and run take it. Deterministic: the same inputs write the same bytes.
A progress line goes to stderr every 10 iterations (not with --quiet).";

/// After the options in `host-sim fmu --help`: what the FMU is and how it steps.
pub const FMU: &str = "\
The FMU (FMI 2.0 Co-Simulation, model identifier structomat_ccc) holds
modelDescription.xml, binaries/<platform>/structomat_ccc.so (the structomat-fmu cdylib,
found next to this executable: build both with `cargo build --release -p
structomat-fmu -p host-sim`, or give --lib) and resources/start.txt.
  parameters   h, the converter's (A, F, H, link1..8 length/mass/inertia, rocker_d,
               mass, mass_inertia, mass_at, shaft_inertia, gravity), its initial state
               (initial.crank_deg, ...) and clutch, ccw, branch_c/g/i_left: fixed at
               initialization, their start values the converter's of the options
  inputs       motor_torque, load_torque (N·m), held over a communication step
  outputs      mode (Integer: 0 free, 1 I0, 2 I6, 3 I8, 4 jam, 5 A6, 6 A8, 7 A68,
               8 coast),
               crank_angle, crank_speed, shaft_angle, shaft_speed, c6, c8, audit.kinetic,
               audit.potential, audit.motor_work, audit.load_work, audit.impact_loss,
               audit.residual
  Every communication step must be a whole multiple n >= 1 of h (to 1e-6 h): the twin
  takes n steps. A step the twin refuses, a non-finite input or a call out of order
  is fmi2Error with its message through the logger; only fmi2Reset steps again.";
