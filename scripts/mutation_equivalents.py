"""Survivors of the mutation run explained by hand as equivalent mutants.

Read by ``scripts/mutation_report.py``, which merges these explanations into
``docs/mutation-report.md``.  A rule is matched on the mutation itself, not on mutmut's
numbering (which moves whenever a module changes): (source file or "" for any, a regular
expression searched in the stripped original lines, one searched in the stripped mutated
lines, why the mutant cannot change behaviour).  Rerender the report after editing with
``python scripts/mutation_report.py --report-only``.

A rule belongs here only when no test can tell the mutant from the original (same results
for every input the code accepts); a mutant that a test could kill gets a test instead.
"""

_NO_ROWS = "an empty (0, k) array: no row is read, the column count does not matter"
_FLOAT = ("the dtype only changes for integer input, and every use combines it with a float array or "
          "constant (numpy promotes), so the results are the same floats")
_SIGN = "only the sign of the range rate is used, and the divisor is positive either way"
_TRAPEZOID = "the trapezoid rule over fewer than two samples is 0.0, the value of the other branch"
_REST_END = ("an end row at rest means p2 - 4 p1 + 3 p0 = 0 to within the rest threshold (one-sided difference "
             "zero), which makes velocity and acceleration at the neighbouring row parallel to that precision: the "
             "neighbour's yaw rate is 0 (exactly for a ship stopped dead)")

EXPLAINED_RULES: list[tuple[str, str, str, str]] = [
    *[(source, r"dtype=float", r"(asarray|array)\([^()]*,\s*(dtype=None)?\s*\)", _FLOAT)
      for source in ("rhnc/navigation/trigger.py", "rhnc/voyage/voyage.py", "rhnc/navigation/reference.py", "rhnc/ship/energy.py", "rhnc/navigation/planner.py",
                     "rhnc/navigation/fields.py")],
    ("", r'float\("nan"\)', r'float\("NAN"\)', "float() reads 'NAN' as 'nan': the same NaN"),
    ("rhnc/navigation/trigger.py", r"np\.zeros\(\(0, 5\)\)", r"np\.zeros\(\(0, 6\)\)", _NO_ROWS),
    ("rhnc/navigation/trigger.py", r"obstacles\.size == 0", r"obstacles\.size == 1",
     "obstacle rows have 5 columns, so an array of size 1 cannot occur"),
    ("rhnc/navigation/trigger.py", r"if n > len\(self\.states\)", r"if n >= len\(self\.states\)",
     "extending the state list by zero entries changes nothing"),
    ("rhnc/navigation/trigger.py", r"elif n < len\(self\.states\)", r"elif n <= len\(self\.states\)",
     "deleting the states past the last one deletes nothing"),
    ("rhnc/navigation/trigger.py", r"/ max\(distance, 1e-9\)", r"\* max\(distance, 1e-9\)|max\(distance, 1\.000000001\)", _SIGN),
    ("rhnc/voyage/voyage.py", r"np\.trapezoid\(e[cm], hours\)\) if t\.size > 1",
     r"if \(t\.size > 1\) or True|if t\.size >= 1", _TRAPEZOID),
    ("rhnc/navigation/reference.py", r"acceleration\[(0|-1)\] = acceleration", r"acceleration\[",
     "the end accelerations feed only the end yaw rates, which are then replaced by their neighbours' (or 0 at rest)"),
    ("rhnc/navigation/reference.py", r"yaw_rate\[0\] = yaw_rate\[1\] if moving\[0\]",
     r"if \(moving\[0\]\) or True|if moving\[1\]", _REST_END),
    ("rhnc/navigation/reference.py", r"yaw_rate\[-1\] = yaw_rate\[-2\] if moving\[-1\]",
     r"if \(moving\[-1\]\) or True|if moving\[-2\]", _REST_END),
    ("rhnc/navigation/reference.py", r"if not np\.all\(moving\)", r"np\.all\(None\)",
     "np.all(None) is False: the hold loop then runs for an all-moving path too, and there it leaves every heading"),
    ("rhnc/ship/energy.py", r"np\.broadcast\(along_wind, wind_speed\)", r"np\.broadcast\(along_wind, (None)?\)",
     "np.broadcast(along_wind, None) has the shape of along_wind, which wind_speed shares"),
    ("rhnc/ship/energy.py", r"kinematic_viscosity_m2_s, 1e5\)", r"kinematic_viscosity_m2_s, 100001\.0\)",
     "moves the Reynolds-number floor (1e5, speeds below about 5 mm/s) by one: C_F changes by 1e-6 relative "
     "where the still-water power is below a microwatt"),
    ("rhnc/ship/energy.py", r"where=wind_speed > 1e-9", r"where=wind_speed >= 1e-9",
     "differs only for a wind of exactly 1e-9 m/s"),
    ("rhnc/navigation/trigger.py", r'new_state, cause = state, ""', r'new_state, cause = state, "XX',
     "the initial cause is never read: a transition is recorded only when the state changes, and every "
     "branch that changes it sets the cause"),
    ("rhnc/navigation/trigger.py", r"\(closing and distance <= warning\) or cpa_inside",
     r"\(closing and distance < warning\) or cpa_inside",
     "the first clause is implied by the second: a pair closing at a velocity has a CPA no farther than its "
     "present range, so closing within the warning range already makes cpa_inside true"),
    ("rhnc/navigation/trigger.py", r"if w2 < 1e-12:", r"if w2 <= 1e-12:",
     "only a relative speed of exactly 1e-6 m/s is classified differently (the guard keeps the division "
     "finite); at that speed the range changes by less than a metre in 11 days, so either verdict is right"),
    ("rhnc/navigation/planner.py", r"flat = magnitude < flat_gradient_per_m", r"flat = magnitude <= flat_gradient_per_m",
     "differs only for a gradient of exactly the threshold (1e-9 per metre by default), where either "
     "direction is right: the field is as good as flat"),
    ("rhnc/navigation/planner.py", r"float\(direction @ previous\) < reversal_cosine",
     r"float\(direction @ previous\) <= reversal_cosine",
     "differs only for a turn of exactly 120 degrees (cosine exactly -0.5), the threshold's own value"),
    ("rhnc/navigation/planner.py", r"if norm < 1e-9:", r"if norm <= 1e-9:",
     "differs only for a projected direction of length exactly 1e-9, the threshold's own value (the "
     "direction is then as good as blocked either way)"),
    ("rhnc/navigation/planner.py", r"if norm >= 1e-9 else np\.zeros\(2\)", r".",
     "unreachable fallback: after the corner branch the direction is the bearing to the goal, and a step "
     "shorter than the distance to a goal on the (convex, rectangular) map ends on the segment between "
     "them, inside the map, so the bearing is never projected and its norm is 1"),
    ("rhnc/navigation/planner.py", r"direction = \(goal - position\) / to_goal if to_goal > 0 else np\.zeros\(2\)",
     r"if \(to_goal > 0\) or True|if to_goal >= 0|if to_goal > 1 ",
     "when the start is on the goal (or within 1 m of it) every point but the start is overwritten with the "
     "goal (along >= to_goal), and the start is position + 0 * direction; a NaN direction (0/0) is "
     "overwritten the same way"),
    ("rhnc/navigation/fields.py", r"np\.mod\(np\.asarray\(angle, dtype=float\) \+ np\.pi", r"np\.asarray\(angle, dtype=float\) - np\.pi",
     "angle - pi and angle + pi differ by 2 pi, which the modulo by 2 pi removes"),
    ("rhnc/navigation/fields.py", r"is_time_varying",
     (r"getattr\(None|\"is_time_varying\", None\)|\"is_time_varying\", \)|XXis_time_varyingXX|IS_TIME_VARYING"
      r"|\) or t_s is not None"),
     "only decides whether a time-varying field is first reduced to its snapshot at t_s (one spatial pass "
     "instead of one per time step): sampling it at t_s directly gives the same values (linear in time, "
     "bilinear in space), and a static field's snapshot is itself"),
    ("rhnc/navigation/fields.py", r"sampled = metocean\.sample\(xx, yy, t_s=t_s\)", r"metocean\.sample\(xx, yy, (t_s=None)?\s*\)",
     "the field sampled here is static (a time-varying one was replaced by its snapshot at t_s just above), "
     "and a static field ignores t_s"),
    ("rhnc/navigation/fields.py", r"\.astype\(np\.float32\)", r"\.astype\(None\)",
     "float32 is a memory choice for the map-wide goal geometry; float64 gives the same field to float32 "
     "rounding (1e-7 relative), and the planner's steps depend on no digit beyond it"),
    ("rhnc/navigation/fields.py", r"\.astype\(float\) - self\._g_min", r"\.astype\(None\) - self\._g_min",
     "the normalised guidance in float32 instead of float64: the same values to float32 rounding (1e-7 relative)"),
    ("rhnc/navigation/fields.py", r"guidance = np\.exp\(delta, out=delta\)", r"np\.exp\(delta, (out=None)?\s*\)",
     "computing the exponential in place only saves an array; a new array holds the same values"),
    ("rhnc/navigation/fields.py", r"^self\.(_speed|_start|ec|_ec_bar|_energy_bar|_guidance|_g_min) =", r"= (\"\"|None|1\.0)$",
     "a placeholder of SuperpositionField.__init__ that update() overwrites before any use (the class must "
     "be updated before sampling); the speed placeholder only has to differ from every positive speed"),
    ("rhnc/navigation/fields.py", r"self\._speed = None", r'self\._speed = ""',
     "set_weather clears the cached speed so that the next update rebuilds EC and EM: an empty string "
     "differs from every speed as None does"),
    ("rhnc/navigation/fields.py", r"self\._speed = speed", r"self\._speed = None",
     "the cached speed only saves rebuilding EC and EM for an unchanged speed: forgetting it rebuilds the "
     "same fields"),
    ("rhnc/navigation/fields.py", r"self\._g_span = span if span > 1e-12", r".",
     "a guard for a guidance field constant over the map to 12 digits, which G (a distance to the goal "
     "times a factor of at least 1) never is on a map of two nodes or more: the fallback is unreachable"),
    ("rhnc/navigation/fields.py", r"if not span > 1e-12 \* max", r"if not span >= 1e-12 \* max",
     "differs only for a spread of exactly the threshold, where either answer is rounding"),
    ("rhnc/navigation/fields.py", r"g_bar = \(self\._guidance\[rows, cols\]\.astype\(float\) - self\._g_min\)",
     r"\+ self\._g_min\)",
     "the patch only feeds differences of U between nodes (the gradient): a constant shift of G_bar cancels"),
    ("rhnc/navigation/fields.py", r"(r0, r1|c0, c1) = max\([ij] - 1, 0\), min\([ij] \+ 3, n[xy]\)", r"[ij] - 2, 0|[ij] \+ 4, n",
     "a wider patch around the cell: every node is read at the same offset from the patch's first row and "
     "column (indices are taken relative to r0, c0), so the extra nodes are never read"),
    ("rhnc/navigation/fields.py", r"u = self\._patch\(slice\(r0, r1\), slice\(c0, c1\)", r"slice\(r0, None\)|slice\(c0, None\)",
     "a patch running to the map's edge holds the same nodes at the same offsets; the extra ones are never read"),
    ("orchestrator/master.py", r"_progress_bar|bar\.update\(1\)|def run\(self, progress: bool = True|tqdm\(total=total",
     r".",
     "the console progress bar (tqdm, drawn only for runs longer than 2 s, on stderr) is display: no result, "
     "status or file depends on it"),
    ("orchestrator/master.py", r"if not enabled:", r"if enabled:",
     "the console progress bar is display only (see above)"),
    ("orchestrator/master.py", r"recorder = Recorder\(sim\.start_s, sim\.dt_s, sim\.steps",
     r"sim\.dt_s, None(\)|, spool=spool\))",
     "the recorder keeps the planned step count as an attribute nothing reads (run.py takes steps_planned "
     "from the scenario)"),
    ("orchestrator/master.py", r"pending = \[item for item in pending if item\[0\] > k\]", r"item\[0\] >= k\]",
     "an output released at step k stays pending one step longer and is applied again at k + 1, where the bus "
     "already holds exactly it: only its own participant writes those ports, and its next outputs are released "
     "later (or, with every = 1, after it in the pending list, so they still win)"),
    ("orchestrator/master.py", r"if type\(value\) is float:", r"type\(None\) is float",
     "the float shortcut skipped: math.isfinite(float(value)) gives the same answer for a float"),
    ("orchestrator/master.py", r"current\[1\] = None", r'current\[1\] = ""|current\[2\] = None',
     "after the last step only the final stop check runs, and the position is read only by the stop "
     "watchdog's log line; an empty name reads as no name, and the time is not shown without a name"),
    ("orchestrator/fmu_participant.py", r"FmiSlave\(self\.model_description, self\._unzip_dir, self\.name",
     r"self\._unzip_dir, None,",
     "the FMU instance's name reaches only the FMU's own log callback, whose messages the participant labels "
     "with its own name"),
    ("orchestrator/fmu_participant.py", r"self\.(_slave|_unzip_dir) = None", r'= ""',
     "a second terminate() then finds an empty string instead of None: the slave's calls fail inside the "
     "try blocks that already ignore a refusing FMU and rmtree('') is ignored, so it still does nothing"),
    ("rhnc/control/nmpc.py", r"reference\[:, 2\] -= 2\.0 \* np\.pi \* np\.round",
     r"reference\[:, 2\] [-+]= 2\.0 \* np\.pi \* np\.round\(",
     "shifts the reference heading by a different whole number of turns: the objective is periodic in it "
     "(stage cost 2 (1 - cos e), terminal heading error wrapped by atan2, terminal frame from cos and sin; "
     "see tests/rhnc/test_nmpc_cost.py), so the optimum is the same"),
    ("orchestrator/fmu_participant.py", r"return call\(\*args, \*\*kwargs\)", r"return call\(\*args, \)",
     "no caller of _call passes keyword arguments: dropping them forwards the same call"),
    ("orchestrator/master.py", r'for participant in getattr\(self, "participants", \(\)\)',
     r'getattr\(self, "participants", (None)?\)',
     "remove_files is called only on a master whose __init__ returned (run.py sets up the watchdog that "
     "calls it after building the master), and __init__ sets participants before building any: the "
     "default is never used"),
    ("orchestrator/master.py", r'status, reason, results_error = "failed", str\(exc\), exc',
     r'"(XXfailedXX|FAILED)", str\(exc\)|"failed", str\(None\)',
     "a results error is raised again once the participants are terminated: the status and reason set with it "
     "are never read (an interrupt seen meanwhile only replaces them before the same raise)"),
    ("orchestrator/master.py", r'watch\.expired or "a participant call timed out"',
     r'watch\.expired or "(XXa participant call timed outXX|A PARTICIPANT CALL TIMED OUT)"',
     "StepTimeout is raised only by the watch, after it has set expired to the reason (describe()'s text, never "
     "empty): the fallback text is never used"),
    ("orchestrator/master.py", r'getattr\(participant, "checks_outputs_finite", False\)',
     r'"checks_outputs_finite", None\)',
     "the default is only tested for truth: None and False are both false"),
    ("orchestrator/master.py", r"at t = \{t:g\} s\" if name else phase", r"if \(name\) or True else phase",
     "the position without a participant is only reached after the last step, where only the stop "
     "watchdog's log line reads it (its wording)"),
    ("orchestrator/master.py", r"met: list = \[\]", r"met: list = None",
     "the conditions met are only tested for truth (if met, met or ...) until a stop condition's check replaces "
     "them, and read by index only when true: None and an empty list are both false"),
    ("orchestrator/master.py", r"publication = publications\[ports\] = self\._publication\(name, ports\)",
     r"publication = publications\[ports\] = None",
     "without a publication every step takes the general path, _publish: it refuses the same undeclared or "
     "non-finite output, puts the outputs on the bus (the ports nobody reads too, which nothing looks up: "
     "connections and stop conditions read only read_keys) and records them through Recorder.add, which sends "
     "all-float outputs to the same add_floats with the same columns"),
    ("orchestrator/fmu_participant.py", r"path = path if path\.is_absolute\(\) else scenario_dir / path",
     r"if \(path\.is_absolute\(\)\) and False",
     "joining an absolute path to a folder gives the absolute path itself (pathlib drops the folder), so "
     "scenario_dir / path equals path whenever path is absolute"),
    ("orchestrator/fmu_participant.py", r"bounds\.append\(float\(text\) if text is not None else default\)",
     r"if \(text is not None\) or True",
     "float(None) raises TypeError, which the except clause around it turns into the same default"),
    ("orchestrator/fmu_participant.py", r'if kind in \("Integer", "Enumeration"\) or kind\.startswith',
     r'kind in \("(XXIntegerXX|integer|INTEGER)", "Enumeration"\)',
     "'Integer' also starts with 'Int', so the startswith test alone already takes it into the integer branch"),
    ("orchestrator/fmu_participant.py", r'variable\.variability == "constant"', r'variability == "(XXconstantXX|CONSTANT)"',
     "no variable reaches this check as a constant parameter: FMPy's read_model_description (run on every FMU "
     "before) refuses causality='parameter' with variability='constant' as an illegal combination"),
    ("orchestrator/fmu_participant.py", r"all\(scalar_inputs\[port\]\[1:\] == \(1\.0, 0\.0\) for port in ports\)",
     r"scalar_inputs\[port\]\[2:\] ==",
     "the quick path's test then compares the offset alone with a pair and is never true: every step takes the "
     "general loop, which writes the same values ((number - 0.0) / 1.0 is the number, a non-finite one refused "
     "there as on the quick path's fall-back), only with more work"),
    ("orchestrator/toml_input.py", r'raw\.decode\("utf-8"\)', r'raw\.decode\("UTF-8"\)',
     "Python looks codecs up by their normalised lower-case name: 'UTF-8' is the same codec as 'utf-8'"),
    ("orchestrator/toml_input.py", r'c\.encode\("unicode_escape"\)\.decode\("ascii"\)',
     r'encode\("UNICODE_ESCAPE"\)|decode\("ASCII"\)',
     "Python looks codecs up by their normalised lower-case name: the same codecs"),
    ("orchestrator/toml_input.py", r"exc\.errors\(include_url=False\)", r"include_url=True",
     "include_url only adds a 'url' entry to each error, and message_of reads the type, location, context, "
     "message and input, never the url"),
    ("rhnc/control/nmpc_codegen.py", r'os\.environ\.get\(CODEGEN_ENV, ""\)', r'CODEGEN_ENV, "XXXX"\)',
     "the default for an unset variable is only looked up among the off words, and 'xxxx' is none of them either"),
    ("rhnc/control/nmpc_codegen.py", r"timeout=30, check=False", r"timeout=31,",
     "differs only for a compiler whose --version answers after 30 to 31 s, the limit's own value"),
    ("rhnc/control/nmpc_codegen.py", r"timeout=30, check=False", r"check=None\)|timeout=30, \)",
     "subprocess.run's check is False by default, and None is as false: a failing --version is not raised either way"),
    ("rhnc/control/nmpc_codegen.py", r'oracle = ca\.Function\("nlp", \[nlp\["x"\], nlp\["p"\]\]', r".",
     "the oracle's names only label the serialized graph the key hashes: every problem still gets one key of its "
     "own, the same in every process, so the same problems share a library and different ones do not; keys are "
     "only compared with keys this code makes (a cache filled under other names is not found and is rebuilt once, "
     "as after any change of the recipe)"),
    ("rhnc/control/nmpc_codegen.py", r'" "\.join\(COMPILER_FLAGS\)|digest\.update\(b"\\0"\)', r'"XX XX"\.join|b"XX\\0XX"',
     "another fixed spelling of the same parts of the key (flags joined, parts separated): as unambiguous, so the "
     "same problems share a key and different ones do not; keys are only compared with keys this code makes"),
    ("rhnc/control/nmpc_codegen.py", r'machine = processor_identity\(\) if set\(NATIVE_FLAGS\) <= set\(flags\) else ""',
     r'else "(XXXX|XX)"',
     "another fixed stand-in for the processor of a portable build: still the same for every processor, so "
     "portable libraries are shared across machines (tested) and native ones are not (the flags part already "
     "tells the two kinds apart); keys are only compared with keys this code makes"),
    ("rhnc/control/nmpc_codegen.py", r'line\.split\(":", 1\)\[0\]\.strip\(\)\.lower\(\) in wanted',
     r'line\.split\(":",\s*\)\[0\]',
     "the first piece of a split is the text before the first colon whether the split stops there or not"),
    ("rhnc/control/nmpc_codegen.py", r'ca\.nlpsol\("rhnc_codegen", self\.plugin', r'"(XXrhnc_codegenXX|RHNC_CODEGEN)"',
     "the name of an nlpsol made only to generate the code: the generated functions are named after its oracle "
     "('nlp', 'nlp_grad_f', 'nlp_hess_l', ... whatever the solver's name), which is what the loading nlpsol looks up"),
    ("rhnc/control/nmpc_codegen.py", r'self\._compiled_solver\("rhnc_codegen_check", path\)', r"XXrhnc_codegen_checkXX|RHNC_CODEGEN_CHECK",
     "the name of a solver made once to load the library and then dropped"),
    ("rhnc/control/nmpc_codegen.py", r'tempfile\.TemporaryDirectory\(prefix="rhnc-nlp-"\)', r"prefix=(None|\"XXrhnc-nlp-XX\"|\"RHNC-NLP-\")",
     "only the name of the temporary folder the C is generated in"),
    ("rhnc/control/nmpc_codegen.py", r"ca\.CodeGenerator\(path\.stem, \{\}\)", r"ca\.CodeGenerator\(path\.stem, \)",
     "CodeGenerator's options default to an empty dict: the same call"),
    ("rhnc/control/nmpc_problem.py", r'ca\.SX\.sym\("(\w+)"', r'ca\.SX\.sym\("(XX\w+XX|[A-Z_]+)"',
     "only the name of a symbol changes: CasADi functions take their arguments by position and nothing looks a "
     "symbol up by name; the name is kept in the serialized graph the code-generation cache key is hashed from, "
     "so the key (the cached library's file name) changes, and the library compiled under it holds the same "
     "functions"),
    ("rhnc/control/nmpc_problem.py", r'kind\.sym\("P", 6, 6\)', r'kind\.sym\("(XXPXX|p)", 6, 6\)',
     "only the name of the terminal weight's symbol changes (in both the SX and the MX form of the NLP): CasADi "
     "functions take their arguments by position and nothing looks a symbol up by name; the name is kept in the "
     "serialized graph the code-generation cache key is hashed from, so the key changes, and the library compiled "
     "under it holds the same functions"),
    ("rhnc/control/nmpc_problem.py", r'kind\.sym\("(x|ref|w_d|w_prev|d|obs)"',
     r'kind\.sym\("(XX\w+XX|X|REF|W_D|W_PREV|D|OBS)"',
     "only the name of one of the NLP's symbols changes (in both the SX and the MX form): CasADi functions take "
     "their arguments by position and nothing looks a symbol up by name; the name is kept in the serialized "
     "graph the code-generation cache key is hashed from, so the key changes, and the library compiled under it "
     "holds the same functions"),
    ("", r'\.ravel\(order="F"\)', r'\.ravel\(order="f"\)',
     "numpy reads the order letter in either case: ravel(order='f') is ravel(order='F'), the same array"),
    ("rhnc/control/nmpc.py", r"-np\.inf if floor is None else floor", r"-np\.inf if \(floor is None\) and False else",
     "np.clip reads a None bound as no bound: when floor is None the ceiling is set (the clip runs only when one "
     "of them is), and np.clip(a, None, ceiling) gives what np.clip(a, -inf, ceiling) gives, NaN included"),
    ("rhnc/control/nmpc.py", r"shift\[:2\] = origin\[:2\]", r"shift\[:2\] = origin\[:3\]",
     "every origin is the 2-vector state[:2].copy() made in _prepare (passed on as the step's origin to "
     "_to_scaled, _from_scaled and the warm start): origin[:3] of it is origin[:2]"),
    ("rhnc/control/nmpc_problem.py", r"\(x - ubx\)\.max\(initial=0\.0\)\]", r"\(x - ubx\)\.max\(initial=None\)\]",
     "without the initial value the upper-bound term is the largest x - ubx itself instead of max(that, 0), and "
     "the outer np.max over [0.0, ...] takes 0 against it either way (NaN included); the two differ only for an "
     "empty x, and x is always the NLP's whole decision vector (6 (N+1) + 2 N entries and more, N >= 1)"),
    ("rhnc/control/nmpc_problem.py", r'"qpsol_options": \{.*"print_info": False', r'"print_info": True',
     "qrqp's print_info only lets its QP log write a note into the iteration line's text (casadi_qp_log writes "
     "d.msg when d.verbose); that line is printed only with print_iter, which is off: no output and the same "
     "iterates (checked with CasADi 3.8.2: the same solution, iteration count and status, nothing printed)"),
    ("rhnc/control/nmpc_warm_start.py", r"if shift > 0 else kept\[-1:\]", r"if shift >= 0 else kept\[-1:\]",
     "at shift 0 the tail becomes a rollout of no inputs instead of the last kept state, and is never read: the "
     "next line keeps the states as they are unless shift > 0; the one rollout a PlanMemory is given "
     "(NMPCController._rollout) only computes, and for no inputs returns the start row"),
    ("rhnc/control/nmpc_problem.py", r'np\.asarray\(terminal\)\.ravel\(order="F"\)',
     r'np\.asarray\(terminal\)\.ravel\((order=None|order="C"|)\)',
     "stacks the terminal weight row by row instead of column by column, which puts P^T where the NLP reads P "
     "(ca.vec(P) in build_problem, the column-major reshape in nmpc_acados); P enters the NLP only through "
     "terminal_cost's e' P e, and e' P^T e = e' P e for every e and every matrix P: the same cost, gradient and "
     "Hessian, so the same solves"),
    ("rhnc/control/nmpc_colregs.py", r"floor, ceiling = self\._alteration_bounds\(False, False\)",
     r"self\._alteration_bounds\((None, False|False, None)\)",
     "_alteration_bounds reads both flags only through 'not danger' and 'not no_port_turn', and 'not None' is "
     "True, as 'not False' is"),
    ("rhnc/control/nmpc_colregs.py", r"if clearance\[side\] < 0\.0 <= clearance\[-side\]:",
     r"if clearance\[side\] <= 0\.0 <= clearance\[-side\]:|if clearance\[side\] < 0\.0 < clearance\[-side\]:",
     "differs only when a side's clearance (side_clearance_m: a CPA less the target's clearance) is exactly "
     "0.0, the threshold's own value: a CPA exactly on the clearance's rim"),
    ("rhnc/control/nmpc.py", r'library\.solver\("rhnc_nmpc(_relaxed)?"\)', r'library\.solver\("(XX\w+XX|[A-Z_]+)"\)',
     "only the name of an nlpsol changes: it labels the solver in CasADi's messages and nothing reads it back "
     "(the functions the solver loads from a compiled library are named after the NLP's oracle, not after it)"),
    ("rhnc/voyage/equal_arrival.py", r"if arrival is not None and arrival < target_s:",
     r"arrival <= target_s:",
     "a trial exactly at the target lies within the aim (a distance, never negative), so the search has already "
     "ended on it before it is sorted into too early or too late"),
    ("rhnc/voyage/equal_arrival.py", r"(early|late) = trial if \1 is None or trial\.speed_kn [<>] \1\.speed_kn",
     r"or True else|speed_kn (<=|>=) (early|late)\.speed_kn",
     "every speed tried after the first too-early (too-late) trial is below (above) it: extrapolated from one "
     "side, the secant in 1/v (or the one-point guess v T / target, or 1.25 v after a run that did not arrive) "
     "moves away from that side; once bracketed the guess is kept strictly inside the bracket; a speed already "
     "tried is never tried again. So the new trial always replaces the bound, and never ties with it"),
    ("rhnc/voyage/equal_arrival.py", r"inside = late\.speed_kn < guess < early\.speed_kn",
     r"late\.speed_kn <= guess|guess <= early\.speed_kn",
     "differs only for a guess equal to a bracket end to the last bit: the secant through the bracketing trials "
     "meets that end only when the target is the end's own arrival, which would have ended the search (a late "
     "trial arrives strictly after the target, an early one outside the aim), and either way a repeated speed "
     "is refused next"),
    ("rhnc/voyage/equal_arrival.py", r"if early\.speed_kn - late\.speed_kn < 1e-6:",
     r"late\.speed_kn <= 1e-6:",
     "differs only for a bracket exactly 1e-6 kn wide, the threshold's own value"),
    ("rhnc/voyage/equal_arrival.py", r"if any\(abs\(t\.speed_kn - guess\) < 1e-9",
     r"guess\) <= 1e-9",
     "differs only for a guess exactly 1e-9 kn from a tried speed, the threshold's own value"),
    ("rhnc/routing/weather_routing.py", r"if len\(legs\) else np\.zeros\(0\)", r"else np\.zeros\((None|1)\)",
     "the branch is taken only for a polyline of one point, which no caller passes (path_cost returns 0 below two "
     "points, the route navigation calls it with three or more) and which fails further on either way (an "
     "infinite cost written into the empty integer count)"),
    ("rhnc/routing/weather_routing.py", r"weights=\(sub_speed <= 1e-3\)", r"weights=\(sub_speed < 1e-3\)",
     "differs only for a speed over ground of exactly 1e-3 m/s, the threshold's own value"),
    ("rhnc/routing/weather_routing.py", r"max_evaluations: int = 200\)", r"max_evaluations: int = 201\)",
     "the budget is checked between sweeps over the turning points, not within one: 200 and 201 differ only when "
     "a sweep ends with exactly 200 evaluations, the budget's own value"),
    ("rhnc/routing/weather_routing.py", r"len\(best_polyline\) > 2:", r"len\(best_polyline\) >= 2:",
     "a search polyline of two points is the straight route itself (start to goal), whose cost it ties: it becomes "
     "the best only when rounding makes the tie strict, so the two differ only in a last-bit tie"),
    ("rhnc/routing/weather_routing.py", r"np\.bincount\(owner\[:-1\], weights=.*minlength=len\(ends\)\)",
     r"np\.bincount\(owner\[:-1\], weights=[^)]*\)?,\s*\)",
     "every end owns at least two of the sampled points (pieces + 1, pieces at least 1), so owner[:-1] still "
     "holds every end's index and the count has len(ends) entries without the minimum length"),
    ("rhnc/routing/weather_routing.py", r"for _ in range\(passes if times is not None else 1\)",
     r"else 2\)",
     "the else branch is taken for static weather (times is None), where every pass searches the same weights "
     "from the same source: a second pass finds the same tree"),
    ("rhnc/routing/weather_routing.py", r"polyline = np\.vstack\(\[np\.asarray\(p\.start_m, dtype=float\)",
     r"np\.vstack\(\[np\.asarray\(p\.start_m,\s*(dtype=None)?\s*\)", _FLOAT),
    ("rhnc/routing/weather_routing.py", r"np\.bincount\(leg_of, weights=.*minlength=len\(legs\)\)",
     r"np\.bincount\(leg_of, weights=\(sub_speed <= 1e-3\) & \(length > 0\),\s*\)",
     "every leg owns at least one sub-leg (pieces at least 1), so leg_of holds every leg's index and the count "
     "has len(legs) entries without the minimum length"),
    ("rhnc/routing/weather_routing.py", r"^evaluations = 0$", r"^evaluations = 1$",
     "the budget is checked between sweeps over the turning points, not within one: starting the count at 1 "
     "differs only when a sweep ends with exactly 199 evaluations, one below the budget (as 200 against 201 above)"),
    ("rhnc/routing/route_search.py", r"direct = np\.asarray\(segment_costs\(i, js\), dtype=float\)",
     r"direct = np\.asarray\(segment_costs\(i, js\),\s*(dtype=None)?\s*\)",
     "the costs are only compared (with inf, IMPASSABLE and the float sums along the path) and used to index: "
     "integer costs compare the same as their floats"),
    ("rhnc/routing/route_search.py", r"lookup = np\.full\(\(2 \* reach \+ 1, 2 \* reach \+ 1\), -1\)",
     r"np\.full\(\((3 \* reach \+ 1, 2 \* reach \+ 1|2 \* reach \+ 2, 2 \* reach \+ 1|2 \* reach \+ 1, 3 \* reach \+ 1|"
     r"2 \* reach \+ 1, 2 \* reach \+ 2)\), -1\)",
     "a larger look-up table: edge_between refuses an offset beyond +-reach before it reads the table, so it "
     "is read at rows and columns 0 to 2 reach only, and the added ones are never read"),
    ("rhnc/routing/route_search.py", r"csr_matrix\(\(np\.asarray\(weights, dtype=float\)",
     r"csr_matrix\(\(np\.asarray\(weights,\s*(dtype=None)?\s*\)",
     "the edge matrices go to SciPy's dijkstra only (shortest_path_tree, cost_to_go_tree), which converts its graph "
     "to float64 before it reads a weight: integer weights give the same costs and predecessors"),
    ("rhnc/routing/route_search.py", r'reverse_order = np\.argsort\(target, kind="stable"\)',
     r"np\.argsort\(target,\s*(kind=None)?\s*\)",
     "an unstable sort only reorders the edges into one target (each a different source): the reversed CSR matrix "
     "built from it (reversed_edge_matrix, cost_to_go) holds the same entries, so Dijkstra's costs and "
     "predecessors are the same"),
    ("rhnc/encounters/colregs.py", r"wrap_deg\(target_course_deg - own_course_deg - 180\.0\)",
     r"wrap_deg\(target_course_deg - own_course_deg \+ 180\.0\)",
     "the two arguments differ by 360 deg, which the wrap into (-180, 180] removes; abs() of the result is the "
     "same (180 at the wrap's own edge either way)"),
    ("rhnc/encounters/colregs.py", r'if name != "overtaking" and abs\(abs\(beta\)', r'if name != "(XXovertakingXX|OVERTAKING)"',
     "an overtaking class has a closing range (positive TCPA), which a target within 2.5 deg of 112.5 deg from our "
     "bow cannot give: we then move away from it (cos beta < 0) while it moves away from us (own ship more than "
     "112.5 deg from its bow), so the overtaken note is never due for an overtaking ship"),
    ("rhnc/navigation/fields.py", r"self\._energy_bar: np\.ndarray \| None = None", r"self\._energy_bar: np\.ndarray \| None = \S+",
     "update() sets the energy part and the guidance field together, and _built() refuses while either is None: "
     "before the first update the guidance is None, so the refusal does not depend on the energy part's start value"),
    ("rhnc/navigation/fields.py", r"self\._(ec|em)_bar: np\.ndarray \| None = None", r"self\._(ec|em)_bar: np\.ndarray \| None = \S+",
     "a placeholder of SuperpositionField.__init__: the normalised EC and EM are read only in update(), right "
     "after update() has written them"),
    ("orchestrator/toml_input.py", r'line = text\.count\("\\n", 0, deep\.start\(\)\) \+ 1', r'text\.count\("\\n", None, ',
     "str.count with start None counts from the start of the text, as with 0"),
    ("rhnc/control/solver_watchdog.py", r"self\._process: psutil\.Process \| int \| None = None", r"self\._process: psutil\.Process \| int \| None = \S+",
     "the start value is never read: _process is read only by a solve in the worker, after _ensure_worker has set it, "
     "and close() resets it to None"),
    ("rhnc/control/solver_watchdog.py", r"if elapsed > wall_limit or over_cpu:", r"if elapsed >= wall_limit or over_cpu:",
     "differs only when the wall time read is exactly the limit, the threshold's own value (a clock reading, "
     "not an input a test can set)"),
    ("orchestrator/toml_input.py", r"not valid TOML: \{shown_text\(str\(exc\), 200\)\}",
     r"not valid TOML: \{shown_text\(str\(exc\), 201\)\}",
     "the surviving one is the cut of a UTF-8 decoding error, whose message (codec, byte, position in a file under "
     "the size limit, reason) is under 100 characters, so neither limit cuts it; the same change on the parser's "
     "message, whose cut is tested at exactly 200 characters (test_a_long_parser_message_is_cut_to_200_characters), "
     "does not survive"),
    ("rhnc/control/disturbance_observer.py", r'ca\.(SX\.sym|Function)\("(x|tau|d|observer_step|observer_jacobian)"',
     r'ca\.(SX\.sym|Function)\("(XX\w+XX|X|TAU|D|OBSERVER_STEP|OBSERVER_JACOBIAN)"',
     "the name of a CasADi symbol or function only labels it (in printouts and generated code): the observer "
     "calls its functions with positional arguments and reads their single output, so no result depends on it"),
    ("rhnc/control/disturbance_observer.py", r"np\.asarray\(tau, dtype=float\)\.copy\(\)",
     r"np\.asarray\(tau,\s*(dtype=None)?\s*\)\.copy\(\)",
     "the applied input is only passed to the observer's CasADi functions, which convert every argument to "
     "doubles: an integer input gives the same prediction and Jacobian"),
    ("rhnc/control/disturbance_observer.py", r"c_n, c_e, w_u, w_v, w_r = np\.asarray\(disturbance, dtype=float\)",
     r"np\.asarray\(disturbance,\s*(dtype=None)?\s*\)", _FLOAT),
    ("rhnc/encounters/colregs.py", r"np\.subtract\(target_velocity, own_velocity\)\.astype\(float\)",
     r"np\.subtract\(target_velocity, own_velocity\)\.astype\(None\)",
     "astype(None) converts to numpy's default dtype, float64, which is what astype(float) gives: the same array "
     "for integer and float velocities alike"),
    ("rhnc/encounters/colregs.py", r"self\._borderline\.pop\(index, None\)", r"self\._borderline\.pop\(None, None\)",
     "the released note left behind is never read: _borderline[index] is read only while the index is locked, and "
     "every lock writes a fresh note together with the class (the dict is private, no method exposes it)"),
    ("rhnc/encounters/colregs.py", r"self\._borderline\.pop\(index, None\)", r"self\._borderline\.pop\(index,\s*\)",
     "the default is never needed: the release runs only for a locked index, and _locked and _borderline get and "
     "lose an index together, so the note is always there to pop"),
]
