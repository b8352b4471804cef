"""Speed of a diagnosis against one calibration of the same data (issue 27 item 6).

    python3 tests/benchmarks/bench_diagnosis_speed.py                      # 5 cases, 3 rounds
    python3 tests/benchmarks/bench_diagnosis_speed.py --rounds 5 --cases 41000:none,41009:water_uptake
    python3 tests/benchmarks/bench_diagnosis_speed.py --commands --roots BEFORE,AFTER   # the ipmc commands

Cases come from the independent generator (tests/discrepancy/independent_generator.py: its own
actuator physics and its own parametrisation of every effect; no data written by the library's
effect code), each seed a different strip (the base drawn ±30–40 % from the user's start), 0.5–2 %
noise, 5 temperatures 19–55 °C, 31 lines 0.05–50 Hz.  Default cases: a null case (41000), one
effect (41009, water uptake), two effects (41038, contact resistance + time delay), a leakage the
band cannot see (41003) and a fluid load (41005, the slowest: Sader's Bessel functions).

Per case and round, interleaved: ``calibrate`` of the baseline (the user's free parameters
alpha0, d, kappa_e, xi, omega_n, default starts and bounds — what ``ipmc calibrate`` runs) and
``diagnose`` of the same data with the same free parameters (defaults: 4000 linearised null draws,
4 null refits).  Printed: median wall and CPU seconds of each, their ratio, the verdict (the same in
every round, else flagged), and the diagnosis's own account (``metadata["profile"]``) per stage —
parameter sets predicted, batched model calls, least-squares fits, fit points (each one residual
vector and Jacobian in one batched model call), wall and CPU seconds.  Each process is single-threaded
(OMP/BLAS pinned to 1); CPU time is the steadier figure on a shared machine.

Measured 2026-11-27, seventh round (h-speed: the per-call overhead of the model path, the same
numbers bit for bit; "before" = main 9d85573, "after" = h-speed a114d03 (its successors change docstrings only), each exported to a plain
folder, interleaved; 2 cores shared with two other benchmarks and a test suite, load 2-4, so
every CPU figure here is ~1.5x the sixth round's)::

    python3 tests/benchmarks/bench_diagnosis_speed.py --commands --rounds 2 --roots BEFORE,AFTER \
        --cases 41038:contact_resistance+time_delay,51600:contact_resistance+time_delay,44102:added_fluid_mass,\
51603:modulus_temperature+diffusivity_temperature,41009:water_uptake

    case                                          ipmc calibrate   ipmc diagnose CPU s   diagnose / calibrate
                                                  CPU s b / a      before    after        before   after
    41038 contact_resistance+time_delay           2.43 / 2.34      15.49     13.88        6.4x     5.9x
    51600 contact_resistance+time_delay           2.28 / 2.41      12.54     11.84        5.5x     4.9x
    44102 added_fluid_mass                        2.31 / 2.45      10.80     10.02        4.7x     4.1x
    not profiled on:
    51603 modulus_temperature+diffusivity_temp.   2.23 / 2.23       6.06      5.84        2.7x     2.6x
    41009 water_uptake                            2.04 / 2.03       6.20      5.80        3.0x     2.9x

Every report.json and model.json the same number by number; median 4.7x -> 4.1x, max 6.4x ->
5.9x: 41038 stays above 5x.  Again with three rounds (``--rounds 3 --cases 41038:...,51600:...``,
load 2-3): 41038 calibrate 2.19 / 2.14 s, diagnose 14.85 -> 12.72 s CPU, 6.8x -> 6.0x; 51600
2.31 / 2.19, 11.53 -> 10.54, 5.0x -> 4.8x; the reports the same.  Stronger than the reports: every batched model output, every
``ModelBatch`` output and every standardised residual vector of an in-process ``ipmc diagnose``
(41038: 24765 arrays; 41009: 7665; 51603: 6888; 44102: 12790) hashed in call order, the same
from both checkouts (PYTHONHASHSEED=0: set iteration orders some calls).  The model calls
alone: the 9963 ``predict.many`` calls of 41038 recorded and replayed in one process (fresh
predictors, 3 rounds, alternating checkouts): 6.8-7.4 s CPU before, 5.1-5.4 after (-24 %), the
outputs' digest the same; valgrind's instruction count of the first 3000 calls 12.17e9 ->
10.38e9 (-15 %; Python's own work, which the change removes, costs more time per instruction
than the numerics that stay).  Each step, on that replay: (1) what does not change between
calls kept — a parameter table's law factors and kelvin temperatures per temperature array
(``ParameterTable.with_columns`` shares them; ``TemperatureLaws.factors``' own cache hashed the
laws record per call), the predictor's frequencies, temperatures and s checked once
(``frequency_response(checked=...)``), the base columns over n sets once per n, T_ref, the
state's fields not copied: 6.67 -> 5.47 s; (2) the values' checks from two reductions each
(extremes) instead of elementwise tests and ``np.all`` (the same outcomes and messages): 5.47 ->
4.87 s (on a loaded machine; ~0.3 s is noise); (3) ``shared_sets`` reading the slice fields'
bytes once, ``State.of``, K and ωn recomputed after parameter effects only when an effect
replaced one of their inputs: ~5.40 -> 5.12 s; (4) small ones (``on_mask`` without a stacked
array, ``_active`` split in one pass): -0.9 % instructions.  tests/physmodel/test_model_path_reuse.py
checks what is kept against fresh evaluations, bit for bit (each test fails on a mutation of
what it guards).

Where 41038's CPU is now (in process, with the hooks): ~14.5 s, the model calls ~5.5 of it; the
rest is the least-squares engine and scipy's trust region around them (lsq.py), the search's
refit bookkeeping, the null scan, start-up and figures.  Not done, and why: a real operand cast
to complex once before a mixed product (numpy has no mixed loops: the cast runs through the
iterator's buffer on every element, ~2.5 % of a call's instructions), because the complex
loops it would then take (broadcast instead of buffered) are other SIMD variants and might
round otherwise; a memo of repeated batches (242 of the 9963 calls repeat one within a
predictor, 334 across predictors of the same model and data: ~3 %); which sets share an
electrode line decided from the table's columns instead of the state's bytes (cheaper, but it
can decide otherwise where two columns round to one state); an array path for the diagnosis's
predictors (the ``ModelBatch`` rows go to dicts and back to an array in ``predict_fast``, ~15 µs
a call, but the wrappers between them are in priors.py and refits.py).

Measured 2026-11-27, sixth round (the next measurement's refits; "before" = 0e3466e, "after" = 9cd2bce,
each exported to a plain folder, interleaved; 2 cores shared with two other sessions, load 2-3)::

    python3 tests/benchmarks/bench_diagnosis_speed.py --commands --rounds 2 --roots BEFORE,AFTER \
        --cases 41038:contact_resistance+time_delay,44102:added_fluid_mass,51600:contact_resistance+time_delay,\
51601:contact_resistance+leakage,51602:time_delay+leakage,51603:modulus_temperature+diffusivity_temperature,\
51604:contact_resistance+time_delay

    case                                          ipmc calibrate   ipmc diagnose CPU s   diagnose / calibrate
                                                  CPU s b / a      before    after        before   after
    41038 contact_resistance+time_delay           1.41 / 1.46       9.78     8.46         6.9x     5.8x
    44102 added_fluid_mass                        1.43 / 1.41       6.60     6.44         4.6x     4.6x
    fresh two-effect strips (never timed before):
    51600 contact_resistance+time_delay           1.41 / 1.51       7.56     7.85         5.3x     5.2x
    51601 contact_resistance+leakage              1.40 / 1.49       3.98     3.98         2.9x     2.7x
    51602 time_delay+leakage                      1.45 / 1.52       5.41     5.23         3.7x     3.4x
    51603 modulus_temperature+diffusivity_temp.   1.50 / 1.44       4.06     4.02         2.7x     2.8x
    51604 contact_resistance+time_delay           1.45 / 1.53       6.98     6.82         4.8x     4.5x

Every report.json and model.json the same number by number.  Median 4.6x -> 4.5x, max 6.9x ->
5.8x: two strips stay above 5x, both contact resistance + delay left ambiguous among four pairs,
where ``ipmc diagnose`` runs the next-measurement search and its refit checks (41038 had gone to
6.7-6.9x with the two-record refit check of 2026-11-27 morning).  What changed: a refit made
before in the same search is not made again (``RecordView.refits``, keyed by the refitted lines'
data and σ, the rival and the starts; on 41038 12 of 36 refits were drive ×1 and ×2 of one band,
the same problem for a linear model under relative noise), and ``vuong_power`` evaluates the
normal CDF with ``scipy.special.ndtr`` (3314 calls, ~75 µs each through ``scipy.stats.norm``).

Then with the two-record plans of the same day merged (short plans offered, next-best second
records, plans from each pair's own best record; main 02e0ef8 against 0e3466e, the
same command, load 3-4 while two benchmarks ran): 41038 7.0x -> 6.8x (it now offers I + Z short at
λ 34.1, whose refits cost what the cache saved), 51600 5.5x / 5.5x, 51604 4.7x / 5.0x, 44102 4.7x,
51601-51603 2.7-3.9x; median 4.7x.  So the diagnosis-time row is not met on the two-effect strips
whose verdict leaves four pairs ambiguous: there ``ipmc diagnose`` spends more on the next
measurement's refit checks than on the diagnosis (41038, in process: diagnose() 3.2 s, the search
~4-5 s).

Tried and withdrawn (review): each rival's starts searched as one multi-start with damped steps
from every start took 41038 to 4.7x and the maximum over these strips to 4.9x, with the same λ on
41038 — but on the refit tests' fixture (576 refits of S and Z records) 33 λ moved, some by two
orders of magnitude both ways, and 2 pairs went from below the target to "separated": another
path ends in another basin, and a start joined a far lower optimum because a refit's cost is
misfit, not noise, and the join test scales with it.  A refit λ is what a separation claim rests
on, so the refits keep their paths.  What the remaining time is: in these refits three starts
often end at one optimum after ~55 evaluations each without joining.  Traced on 41038 (truth
contact resistance + delay, rival contact resistance + amplifier, an I record): starts 0 and 1 end
at the same values to 5 digits, the amplifier's two time constants collapsed onto one (τ₁ = τ₂,
where their Jacobian columns coincide), start 2 at the same cost with other mechanical values (an I
record does not see them).  JᵀJ is near-singular there, so the Gauss–Newton landing the basin test
uses falls far off.  Grouping several starts' points in one model call (the effect predictor's
rows are independent of their call: bitwise on 126 effect combinations) was measured too and is
slower: started together, a later start cannot join an earlier optimum before it exists, and the
diagnosis's singles took 1683 points instead of 1040.

Measured 2026-11-26, fifth round (h-d44: why strip 44102's pair refits with viscous_fluid take so
many points; 2 cores shared by ~6 sessions, load 3-5): "before" = 133819a (main, exported to a
plain folder), "after" = this branch, interleaved as in the third round::

    python3 tests/benchmarks/bench_diagnosis_speed.py --commands --rounds 2 --roots BASE,. \
        --cases 44102:added_fluid_mass,41005:added_fluid_mass,43103:added_fluid_mass,41000:none,41038:contact_resistance+time_delay
    python3 tests/benchmarks/bench_diagnosis_speed.py --commands --rounds 2 --roots BASE,. \
        --cases 45101:added_fluid_mass,45102:added_fluid_mass,45103:added_fluid_mass,45104:added_fluid_mass,46101:added_fluid_mass,46102:added_fluid_mass

    case                                  ipmc calibrate   ipmc diagnose CPU s   diagnose / calibrate
                                          CPU s b / a      before    after        before   after
    44102 added_fluid_mass                1.70 / 1.64      8.82      7.91         5.2x     4.8x
    41005 added_fluid_mass                1.71 / 1.67      6.77      6.57         4.0x     3.9x
    43103 added_fluid_mass                1.62 / 1.62      7.46      6.82         4.6x     4.2x
    41000 none                            1.69 / 1.72      4.95      4.77         2.9x     2.8x
    41038 contact_resistance+time_delay   1.80 / 1.72      7.49      7.74         4.2x     4.5x
    fresh fluid strips (not profiled on):
    45101 added_fluid_mass                1.63 / 1.64      7.15      6.65         4.4x     4.1x
    45102 added_fluid_mass                1.68 / 1.69      6.61      6.38         3.9x     3.8x
    45103 added_fluid_mass                1.68 / 1.62      5.00      4.80         3.0x     3.0x
    45104 added_fluid_mass                1.67 / 1.71      7.64      7.50         4.6x     4.4x
    46101 added_fluid_mass                1.63 / 1.70      4.74      4.77         2.9x     2.8x
    46102 added_fluid_mass                1.65 / 1.82      4.98      5.12         3.0x     2.8x

All within 5x now; 44102 by a margin of ~0.3 s CPU (5.2x on main in this round, 5.6x in the
fourth).  Again with three rounds (``--rounds 3 --cases 44102:added_fluid_mass,43103:added_fluid_mass``):
44102 calibrate 1.57 / 1.59, diagnose 8.54 -> 7.61 s CPU, 5.5x -> 4.8x; 43103 1.43 / 1.54, 6.87 ->
6.41, 4.8x -> 4.2x.  41038 (the same fit points before and after) shows the noise of a CPU time here,
±0.25 s.  Fit points of a whole diagnosis (``diagnose()``, ``metadata["profile"]``, before ->
after): 44102 4686 -> 4263, 43103 3589 -> 3268, 41005 3150 -> 3095, 41009 3041 -> 2840, 44103
4201 -> 3984, 45101 4372 -> 4197, 45102 3029 -> 2829, 45104 3382 -> 3047; 17 strips 52718 ->
50380 (41000, 41003, 41038, 44101, 44104, 44105, 45103, 46101, 46102 within ±150).

Why the pair refits ran long (every pair refit of 44102 replayed, each point's cost, Gauss–Newton
decrement and step, scipy's own iteration log and the profile search's secant steps): the three
refits of diffusivity_temperature + viscous_fluid took 240 (two starts, 110 and 130), 111 and 110
points, the same optimum each (costs equal to 1e-9).  Per start: 15 trust-region
points until the crawl test fired (as designed: steps 0.9-3.5e-3 against a Gauss–Newton step of
0.3-0.7 along log10 ν, gains 3e-4 a point of a 0.08 decrement), 20 in the profile search, then
~75 more trust-region points.  Causes, each a defect of the profile search
(``lm_steps.profile_search``):

* it stopped at its first step past the profile's minimum: the cost rose there and the search
  read that as "the profile does not fall that way", though (Jᵀr)_k had changed sign — the minimum
  was bracketed (z of log10 ν 0.45 -> 0.86, the optimum at 0.62).  The trust region then crawled
  the remaining 0.17 for ~75 points, at a pace (20-30 % of the decrement per 10 points) just
  above the crawl test's 10 %;
* once bracketed, plain regula falsi crept up from one side (the far end never replaced: 12
  steps of 0.01-0.02);
* each secant step moved k alone, out of the curved valley (the cost 155 -> 1.5e3-1.6e4) and the
  inner fit needed 4-5 points back;
* (found on 41005 once the last was fixed) an inner Gauss–Newton step of a coordinate at its bound
  (fractional_transport's β at 1) was clipped there, leaving the others' step aimed at a point
  they no longer reached: the inner fit gave up with the cost risen, and the engine repeated
  searches that found nothing to its 200-point budget.

Not the cause: the Jacobian's conditioning (4e3-2e4 on these refits), the starts (all in the one
basin, 0.3-0.5 in z from the optimum along the valley), x_scale (fourth round).  Fixed: a step
past the minimum brackets it (the search goes on by regula falsi), the Illinois modification (the
retained end's derivative halved when the same end is replaced twice), each step starting the
others where the last point's Gauss–Newton model puts them at the new k (along the valley's
tangent), coordinates at a bound that the step pushes outwards held there, and a search ended
after three secant steps without a lower point (a kink of the model: Sader's Ω is held constant
above log10 Re = 4, and there the inner fits move k back and forth).  A test (a profile step past
the minimum of the closed-form valley of tests/estimation/test_lsq_crawl.py) fails on the old
search in 6 of 12 seeds.  The pair refits: the three refits of a pair (from a's fit, from b's fit,
from the joint linearised start) are now one multi-start (``Refitter.refit(more=...)``), so a later
start that reaches an earlier optimum stops there.  After both, that pair takes 231 points.

Left, and why: (1) in a pair refit the later starts take as many points as the first (over the
88 pair refits of the 24 strips below: 10842 points, 2415 of them in start 0), because they join an earlier
optimum only when their Gauss–Newton step lands within 0.1 standard errors of it (1 since 2026-11-27), which in the
curved valley is at the very end; they do matter (45104: start 1 found a cost 2.07 lower than start
0).  A join test along the valley belongs in the engine (lsq.py, h-cal's).  (2) Later starts that
never come near the best (44102: 238 points in 3 starts ending > 100 above the best, one from the
user's start with amplifier_bandwidth's typical values at cost 2.7e5 running its 200-point budget;
45101 379, 44103 215): abandoning such a start is again the engine's.  (3) The slow crawls under
the 10 % test (44102's viscous_fluid single, start 2: 160 points).  Tried and dropped: the crawl
test at 50 % (CRAWL_GAIN 0.5): 44102 4020 points, but it fired at that kink of Ω (a refit of the
verdict stage 92 -> 190 points, its cost 5e-7 higher) and sent a start of 45101 to its budget; over
13 strips 39890 points against 40216 with the 10 % test (1 %).  A "fruitless
search" rule (a search that gained less than 10 % of its decrement returns its start, and the
engine searches no more): in these valleys the Gauss–Newton decrement overstates the gain left
10-35x, so it stopped good searches (the synthetic valleys 552 -> 710 points, 43103's pairs 559 ->
972).

Verdicts and names identical, ``diagnose()`` from both checkouts with the same seeds, on 24 cases:
the speed cases 41000, 41009, 41038, 41003, 41005, 43103, 44101-44105, the fresh fluid strips
45101-45104, 46101, 46102, and the fluid detection set 1020-1023, 5015-5017.  The numbers move at
the fits' convergence level: candidate LRs by at most 8e-8 on all but one case, 1.5e-5 on 41038
(distributed_cpe: a fit that had stopped on scipy's ftol inside a crawl, now 7.3e-6 lower in cost);
pair costs by at most 4e-7 (fits ending on scipy's ftol in a flat valley), except where main's pair
refit had not converged: 5016 series_cpe + viscous_fluid (every start of main's three refits at its
200-point budget) now 0.003 lower, 1021 series_cpe + viscous_fluid 4e-6 lower.  Fit points over
the 24: 81956 -> 77466 (5015 4240 -> 4413, the one that grew).  The report files differ in those
digits.

Review fixes of the fifth round (session 11, 2026-11-26): a point whose inner fit did not get back
to the valley floor (cost up > 4 s²) no longer becomes a bracket end, and only a point lower by
more than INNER_DECREMENT·s² resets the stale count.  The same 24 cases, ``diagnose()`` from the
merged fifth round and from the fixed search (the review's /tmp/d44/instr.py): verdicts and names
identical 24/24, candidate LRs the same to 1.3e-13, candidate costs to 2.2e-12; fit points 77416 ->
77021 (44102 4263 -> 4225; 45101 4197 -> 4308, the one that grew).  On the crawl test's problem
(tests/estimation/test_lsq_crawl.py, 12 seeds × 2 orders, max_nfev 60) the evaluations are 646
before the fifth round, 544 after it, 526 with the fixes; a profile secant convergence test and a
bisection safeguard the review also proposed cost 614 and 568 there and were not taken.

Measured 2026-11-26, fourth round (h-fluid: why the fluid-load strips' viscous_fluid refits run
long; 2 cores shared by ~6 sessions): "before" = c0116c8 (main, exported to a plain folder),
"after" = this branch, interleaved as in the third round::

    python3 tests/benchmarks/bench_diagnosis_speed.py --commands --rounds 2 --roots BASE,. \
        --cases 41005:added_fluid_mass,43103:added_fluid_mass,44102:added_fluid_mass,44105:added_fluid_mass,41000:none
    python3 tests/benchmarks/bench_diagnosis_speed.py --commands --rounds 2 --roots BASE,. \
        --cases 45101:added_fluid_mass,45102:added_fluid_mass,45103:added_fluid_mass,45104:added_fluid_mass

    case                                  ipmc calibrate   ipmc diagnose CPU s   diagnose / calibrate
                                          CPU s b / a      before    after        before   after
    41005 added_fluid_mass                1.57 / 1.55      8.06      6.75         5.1x     4.3x
    43103 added_fluid_mass                1.57 / 1.59     10.35      7.27         6.6x     4.6x
    44102 added_fluid_mass                1.60 / 1.57     10.37      8.81         6.5x     5.6x
    44105 added_fluid_mass                1.70 / 1.66      5.07      4.57         3.0x     2.8x
    41000 none                            1.64 / 1.57      4.89      4.78         3.0x     3.0x
    fresh fluid strips (not profiled on):
    45101 added_fluid_mass                1.45 / 1.47      6.53      6.34         4.5x     4.3x
    45102 added_fluid_mass                1.45 / 1.40      6.83      5.89         4.7x     4.2x
    45103 added_fluid_mass                1.38 / 1.38      4.61      4.34         3.3x     3.2x
    45104 added_fluid_mass                1.42 / 1.50      6.78      7.33         4.8x     4.9x

Still above 5x: 44102 (5.6x).  Why the refits ran long (every start of ``_solve`` recorded on
43103: its points, scipy's nfev/njev, the path in z and the Jacobian's column norms and
condition): not the starts (six per candidate refit, as designed), not x_scale (``x_scale="jac"``
took 270 points where 1.0 took 125 on the data refit, the same optimum), not a one-sided
difference at a bound.  The trust region crawled: on the data's viscous_fluid refit it reached
1.2e-3 above the optimum in 25 points and spent 100 more moving log10 ν by 0.28 (z 0.134 ->
0.202, ξ and ωn following) for that 1.2e-3; condition of J 6e5, the √(ρ_f η) column 1e5 against
ν's 1e3.  The Gauss–Newton step along the valley was 35x too long (its ν component 2.36 where
the optimum was 0.06 away) — at a noise-size cost (s² ≈ 0.9) JᵀJ underrates the curvature along
the direction the data barely determine (the neglected Σ rᵢ∇²rᵢ) — and the valley is curved, so
even 1 % of that step raised the cost by 0.02: scipy's trust region rejected step after step.
The later starts, which the engine stopped when their Gauss–Newton step landed within 0.1 standard
errors of an earlier optimum (1 since 2026-11-27), crawled the same valley, where that step is wrong until the very
end (they joined after 54-132 points, or ran into the 200-point budget: 705 of the refit's 830
points).  Tried and dropped: a line search along the Gauss–Newton step (straight or bent by its
geodesic acceleration: the valley leaves a straight line at once), Newton steps on a
finite-difference Hessian (its differences of finite-difference gradients drown the valley's
eigenvalue in round-off), a second crawl test (the decrement not halving in 10 points: more
points on 43103 and 41005).  Taken (physmodel/estimation/lsq.py, lm_steps.py): when the trust
region crawls (10 of its points gaining < 10 % of the Gauss–Newton decrement it had, that
decrement > 1e-4·s²) the valley is searched as a profile — the coordinate most aligned with
JᵀJ's flattest eigenvector fixed, the others fitted by Gauss–Newton, that coordinate moved by
secant steps on (Jᵀr)_k (the profile's derivative) — and a fresh trust region resumes.  On a
synthetic valley with a closed-form profile (tests/estimation/test_lsq_crawl.py) the engine
before spent its 200-point budget 0.07-0.5 short of the optimum; after, 22-26 points to it.
Fit points of a whole diagnosis (``metadata["profile"]``, before -> after): 41005 3978 -> 3141,
43103 4897 -> 3619, 44102 5817 -> 4714, 44105 2375 -> 2079, 45102 3685 -> 3046, 45104 3429 ->
3451, 41000 2598 -> 2594.

Verdicts and names identical on all 22 cases compared (``diagnose()`` from both checkouts, same
seeds): the speed cases 41000, 41009, 41038, 41003, 41005, 43103, 44101-44105, and the fluid
detection set (independent ``added_fluid_mass``: 1020-1023 and 5015-5017, the bench_discrepancy
plans ``--first-seed 1000 --n-per-label 4`` and ``--first-seed 5000 --n-per-label 3``, and
45101-45104).  The numbers move at the fits' convergence level: candidate LRs by at most
2.6e-7 on 20 of the 22 cases, 3.7e-5 on two (41038 distributed_cpe, 5017 viscous_fluid: fits
that had stopped on scipy's ftol inside a crawl); the final model's cost by at most 1.3e-7.
bench_discrepancy.py ``--generator independent --first-seed 1000 --n-per-label 4 --null 0
--labels added_fluid_mass --workers 1 --no-real`` from both checkouts: the same four outcomes.
The report files differ in those digits (the benchmark's number-by-number comparison says DIFFER).

Measured 2026-11-26, third round (h-dspeed2: figures, the null scan, the CPE-order and fluid
batches; 2 cores shared by ~6 sessions, load ~2): the commands as the issue measures them,
child-process CPU, median over rounds.  "Before" = f5fe250 (this work's base, exported to a plain
folder), "after" = this branch; the benchmark runs the commands from both, interleaved with the
order alternating, every process from bytecode (``--roots``: PYTHONDONTWRITEBYTECODE is set here,
and a checkout without __pycache__ compiled every module in every process, ~0.1 s, which had made
this worktree's calibrate look slower and its ratio better), and compares report.json and
model.json number by number: the same on every case below (verdicts, names, costs, thresholds,
LRs, the next-measurement search)::

    python3 tests/benchmarks/bench_diagnosis_speed.py --commands --rounds 3 --roots BASE,. \
        --cases 41000:none,41009:water_uptake,41038:contact_resistance+time_delay,41003:leakage,41005:added_fluid_mass,43103:added_fluid_mass
    python3 tests/benchmarks/bench_diagnosis_speed.py --commands --rounds 2 --roots BASE,. \
        --cases 44101:none,44102:added_fluid_mass,44103:fractional_transport,44104:contact_resistance,44105:added_fluid_mass

    case                                  ipmc calibrate   ipmc diagnose CPU s   diagnose / calibrate
                                          CPU s b / a      before    after        before   after
    41000 none                            1.42 / 1.45      4.89      4.52         3.4x     3.1x
    41009 water_uptake                    1.47 / 1.48      5.87      5.22         4.0x     3.5x
    41038 contact_resistance+time_delay   1.48 / 1.47      7.38      6.70         5.0x     4.6x
    41003 leakage                         1.43 / 1.44      4.39      3.70         3.1x     2.6x
    41005 added_fluid_mass                1.49 / 1.46      8.32      7.57         5.6x     5.2x
    43103 added_fluid_mass                1.46 / 1.41     10.50      9.56         7.2x     6.8x
    fresh strips (not profiled on), two rounds:
    44101 none                            1.49 / 1.49      5.05      4.37         3.4x     2.9x
    44102 added_fluid_mass                1.50 / 1.51     10.58      9.86         7.0x     6.5x
    44103 fractional_transport            1.55 / 1.45      7.99      6.84         5.2x     4.7x
    44104 contact_resistance              1.40 / 1.47      5.07      4.47         3.6x     3.0x
    44105 added_fluid_mass                1.39 / 1.43      4.99      4.48         3.6x     3.1x

Median 4.5x -> 4.1x (profiled set), 3.6x -> 3.1x (fresh).  Still above 5x: the fluid-load strips
whose viscous-fluid refits run long (41005 5.2x, 43103 6.8x, 44102 6.5x; 44105, also a fluid
load, is 3.1x).  What changed, each the same numbers bit for bit (every model call of a diagnosis
of 41000, 41005, 41038 and 43103 recorded on the base and replayed, every null-scan Gram call of
41005 and 43103 replayed, the figures compared pixel for pixel):

* the two figures of ``ipmc diagnose`` drawn on one canvas (``plots.residual_bode_pair``: the
  baseline's, written, then the model's and residuals' lines set to the final model and the limits
  recomputed) with fixed margins instead of ``tight_layout`` (a second full draw per figure):
  0.94 -> 0.56 s CPU, matplotlib's import included;
* ``fractional_transport`` (a kernel effect, one ŝ grid per call) in one model call for the sets
  where it is on, each on its own ŝ (``evaluate_grid`` takes per-set points): a Jacobian's
  finite-difference set of β had cost a second full call (pairs with it 2.15 ms a point on 41005
  against 1.4-1.6 for the others);
* the null scan's constrained LR (``_constrained_lr_gram``): the one-parameter subsets in closed
  form and Σ b_j d_j added row by row, 0.27 -> 0.18 s on 43103;
* Γ of the fluid load on the distinct (width, viscosity) rows of a batch instead of ``np.unique``
  over every Reynolds number (a few per cent of a fluid call: the Bessel functions themselves stay);
* parameter rows to dicts through one ``tolist()``.

Where ``ipmc diagnose`` spends its CPU now (in-process timers, seconds): 41005 start-up 0.65,
``diagnose()`` 5.3, the next-measurement search 1.0, the figures 0.6; 43103 0.67, 7.05, 1.36,
0.55.  ``ipmc calibrate`` is 1.45, mostly start-up and its figure.  Inside ``diagnose()`` on
43103 the model is 4.2-4.6 s (replayed alone), three quarters of it in calls with the fluid load, where the
Bessel functions of Sader's Γ (``scipy.special.kve`` of complex arguments, 1.27 million Reynolds
numbers, none repeated between calls: every fit step moves the viscosity) are ~0.7 s and another
~0.5 s in the next-measurement search; the estimation layer is ~2.6 s (the model replaced by the
recorded outputs: scipy's trust region, the range penalties of ``priors``, residuals, the null
scan).  The viscous-fluid refits themselves are the bulk: 849 points for the single-candidate
refit on 43103, 969 for its four null refits, 933 in its pairs, at 1.4-2.8 ms a point.  Not done
here: a faster Γ (its numbers would change at round-off and with them the fits' paths), the
next-measurement search (physmodel/estimation/next_measurement*.py, another helper's), the range
penalties (priors.py), and sharing one model call between the quantities of a joint diagnosis
(``JointData.predictor`` calls the model once per quantity; none of these cases is joint).

Second round, older table (measured 2026-11-26 on the model layer; 2 cores shared by ~6 sessions,
load 2-4): the commands as the issue measures them, child-process CPU.  "Before" = main at 795c454, "after" = the
same plus this work (h-dspeed), interleaved per case and round (before/after order alternating);
the reports (report.json) compared number by number::

    python3 tests/benchmarks/bench_diagnosis_speed.py --commands --rounds 2             # after: 3.5x median, 5.2x max
    # before/after interleaved: the same two commands run from /work/main and from this branch
    case                                  ipmc calibrate   ipmc diagnose CPU s   diagnose / calibrate
                                          CPU s            before    after        before   after
    41000 none                            2.07 / 2.18      8.25      7.10         4.0x     3.3x
    41009 water_uptake                    2.03 / 1.88      8.94      7.26         4.4x     3.9x
    41038 contact_resistance+time_delay   2.06 / 1.96     11.98      9.50         5.8x     4.8x
    41003 leakage                         2.02 / 2.19      6.98      6.26         3.4x     2.9x
    41005 added_fluid_mass                2.03 / 2.03     13.71     10.85         6.8x     5.4x
    fresh strips, one round (--cases 43101:none,43102:contact_resistance,43103:added_fluid_mass,
    43104:leakage,43105:water_uptake):
    43101 none                            2.05 / 2.09      9.39      7.43         4.6x     3.6x
    43102 contact_resistance              2.04 / 2.06      9.41      8.73         4.6x     4.2x
    43103 added_fluid_mass                2.10 / 2.11     18.53     13.93         8.8x     6.6x
    43104 leakage                         2.06 / 2.12      7.44      6.74         3.6x     3.2x
    43105 water_uptake                    2.23 / 2.15      9.32      7.76         4.2x     3.6x

Every report is the same before and after, number for number (verdicts, names, costs, null
thresholds, candidate LRs, the next-measurement search).  The model's outputs are the same bit for
bit: every ``predict_many`` call of a diagnosis, recorded on main and replayed on this branch, gives
the same array (41000, 41005, 41038 with the next-measurement search, 43103; max relative
difference 0).  That replay times the model layer alone (CPU s, main → this branch): 41005 7.4 →
3.9, 41038 4.2 → 2.5, 41000 3.7 → 2.2, 43103 9.6 → 5.8.  Where it went: Sader's Bessel functions
evaluated once per distinct Reynolds number (the finite-difference sets of every parameter but the
viscosity's repeat the point's), an actuator batch's shared electrode lines evaluated once
(``ActuatorModel.evaluate_state``), the temperature-law factors kept per (laws, T, T_ref), and
sets that name the same parameters — a fit's points and Jacobian columns — read into one array
instead of a dict, a table and a model per call.

Still above 5x: the fluid-load strips (41005, 43103).  ``ipmc diagnose`` on 41005 is now
(CPU s) start-up 0.8, ``diagnose()`` 7.5, the next-measurement search 1.5 (ambiguous verdicts
only), the two figures 1.4; ``ipmc calibrate`` is 2.1, of which 1.35 is importing scenarios.cli,
the estimation package and matplotlib.  Inside ``diagnose()`` the model is now about half (3.9 s);
the rest is the estimation layer (least squares, the null statistics: ``_constrained_lr_gram`` alone
is 0.85 s of 7.1 on 41038).  On 43103 the model is 5.8 s of 10 (Bessel functions ~0.6 s for 1.27
million Reynolds numbers, the modal sums of the higher-mode candidates, the non-batchable
fractional_transport in the pairs).

Earlier round (the estimation layer).  "Before" = e6a666c (main at the start of that work), one
round; "after" = that branch, three rounds (median)::

    python3 tests/benchmarks/bench_diagnosis_speed.py --rounds 3       # after
    python3 tests/benchmarks/bench_diagnosis_speed.py --rounds 1       # before (run in a copy of e6a666c)

    case                                  diagnose CPU s     calibrate   diagnose / calibrate (CPU)
                                          before   after     CPU s       before   after
    41000 none                            30.4     11.65     0.017       1563x    683x
    41009 water_uptake                    32.0     13.12     0.016       2070x    835x
    41038 contact_resistance+time_delay   37.6     12.32     0.059        630x    209x

Verdicts identical before and after (none; named water_uptake; ambiguous among the declared
twins), as are the messages and the null thresholds (9.916, 11.823, 8.749); two more strips checked
the same way (``--cases 41003:leakage,41005:added_fluid_mass``: none, and ambiguous viscous_fluid /
distributed_cpe) keep their thresholds (9.8103, 10.4189), nonlinearity ratios and top-3 LRs to the
printed digits, at 21.8 → 8.6 s and 31.5 → 17.5 s CPU.  The library's
``calibrate`` is 16-60 ms here (one model class evaluated on states built as arrays, 24-88 batched
calls), so no diagnosis — at least 16 candidate refits, each a fit of a different model — comes
within 5× of it.  What the issue measured (31.7 s vs 2.0 s) were the commands, whose calibrate is
mostly start-up, report and figure; on seed 41009 (CPU, ``/usr/bin/time``)::

    ipmc calibrate sweep.csv --set base.json --kind actuator --free alpha0 --free d --free kappa_e \
        --free xi --free omega_n --out cal --force --quiet --accept-misfit                 2.0 s
    ipmc diagnose --data sweep.csv --set base.json --kind actuator --free alpha0 --free d \
        --free kappa_e --free xi --free omega_n --seed 41009 --out dia --force --quiet    before 32.5 s (16×)
                                                                                         after  15.8 s (7.9×)

Where the time went then (seed 41009): the null refits 6.2 s CPU (72 fits, 1767 points),
the single-candidate refits 3.5 s (19 fits, 1032 points), signatures and the look-elsewhere scan
1.9 s, pairs and verdicts 1.2 s.  Under cProfile 80 % of a diagnosis is inside the effect model's
``predict_many`` (physmodel/effects/library.py): 3.65 ``frequency_response`` calls per batched
call (one per distinct set of effect values, so a Jacobian of a k-parameter candidate costs 1 + k
of them) and 24 % in ``apply_values``, one validated ``IPMCParameters`` per parameter set.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "discrepancy"))

from physmodel import IPMCParameters  # noqa: E402
from physmodel.estimation.calibration import calibrate  # noqa: E402
from physmodel.estimation.discrepancy import diagnose  # noqa: E402

FREE = ("alpha0", "d", "kappa_e", "xi", "omega_n")
CASES = "41000:none,41009:water_uptake,41038:contact_resistance+time_delay,41003:leakage,41005:added_fluid_mass"
STAGES = ("baseline", "signatures", "singles", "null", "pairs", "verdicts")


def _case(spec: str):
    import independent_generator as ig

    seed, label = spec.split(":", 1)
    sweep, truth = ig.make_case(int(seed), label, baseline_lambda=False)
    return int(seed), label, sweep, IPMCParameters.from_dict(dict(truth["library_start"])), truth["expected"]


def _timed(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def run(cases: str, rounds: int) -> list[dict]:
    rows = []
    for spec in cases.split(","):
        seed, label, sweep, base, expected = _case(spec)
        cal = {"wall": [], "cpu": []}
        dia = {"wall": [], "cpu": []}
        verdicts, profile = set(), None
        for _ in range(rounds):          # interleaved: a drift of the machine hits both alike
            c, w, p = _timed(lambda: calibrate(sweep, base, FREE))
            cal["wall"].append(w)
            cal["cpu"].append(p)
            d, w, p = _timed(lambda: diagnose(sweep, base, kind="actuator", free=FREE, alpha=0.05, seed=seed))
            dia["wall"].append(w)
            dia["cpu"].append(p)
            verdicts.add((d.verdict, tuple(sorted(d.named))))
            profile = d.metadata.get("profile", {})       # absent before issue 27 item 6
        med = {k: {q: float(np.median(v)) for q, v in x.items()} for k, x in (("calibrate", cal), ("diagnose", dia))}
        row = dict(seed=seed, label=label, expected=expected, verdicts=sorted(verdicts), profile=profile,
                   calibrate_evaluations=c.n_evaluations, calibrate_calls=c.n_model_calls, **med)
        rows.append(row)
        _print(row)
    return rows


def _child_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def _same_numbers(a, b, path="") -> list[str]:
    """Where two reports (parsed JSON) differ, number by number; timings and the output folder's
    name (in the model file's provenance) are left out."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for k in sorted(set(a) | set(b)):
            if k in ("elapsed_s", "seconds", "cpu_s", "command"):
                continue
            out += ([f"{path}/{k}: on one side only"] if k not in a or k not in b else
                    _same_numbers(a[k], b[k], f"{path}/{k}"))
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} vs {len(b)} items"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in _same_numbers(x, y, f"{path}[{i}]")]
    same = a == b or (isinstance(a, float) and isinstance(b, float) and a != a and b != b)
    return [] if same else [f"{path}: {a!r} vs {b!r}"]


def run_commands(cases: str, rounds: int, roots: list[Path] | None = None) -> list[dict]:
    """The issue's own measure: ``ipmc calibrate`` vs ``ipmc diagnose`` on the same sweep file and
    free parameters, as a user types them (start-up, report and figures included), interleaved;
    CPU of each child process (RUSAGE_CHILDREN).  ``roots``: checkouts to run the commands from
    (PYTHONPATH), interleaved per round with their order alternating (before / after a change);
    their report.json and model.json are then compared number by number."""
    from physmodel.data.sweep import write_csv

    ipmc = [sys.executable, "-m", "scenarios.cli"]
    free = [x for n in FREE for x in ("--free", n)]
    roots = roots or [ROOT]
    # every root runs from bytecode: with PYTHONDONTWRITEBYTECODE set, a checkout without
    # __pycache__ would compile every module in every process (~0.1 s CPU, seen as a slower
    # calibrate in one root), so the bytecode goes to one cache outside the checkouts, filled by
    # an untimed run of each command per root below
    base_env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    base_env.setdefault("PYTHONPYCACHEPREFIX", str(Path(tempfile.gettempdir()) / "bench_diagnosis_speed_pyc"))
    warm = True
    rows = []
    for spec in cases.split(","):
        seed, label, sweep, base, expected = _case(spec)
        with tempfile.TemporaryDirectory() as tmp:
            t = Path(tmp)
            write_csv(sweep, t / "sweep.csv")
            (t / "base.json").write_text(json.dumps(base.to_dict()))
            times: dict = {}
            codes: dict = {}
            for r in range(-1 if warm else 0, rounds):        # round -1: the untimed warm-up
                for i in (range(len(roots)) if r % 2 == 0 else reversed(range(len(roots)))):
                    env = dict(base_env, PYTHONPATH=str(roots[i]), MPLBACKEND="Agg")
                    cmds = {
                        "calibrate": ipmc + ["calibrate", "sweep.csv", "--set", "base.json", "--kind", "actuator",
                                             *free, "--out", f"cal{i}", "--force", "--quiet", "--accept-misfit"],
                        "diagnose": ipmc + ["diagnose", "--data", "sweep.csv", "--set", "base.json", "--kind",
                                            "actuator", *free, "--seed", str(seed), "--out", f"dia{i}", "--force",
                                            "--quiet"],
                    }
                    for k, c in cmds.items():
                        c0 = _child_cpu()
                        p = subprocess.run(c, cwd=t, env=env, capture_output=True, text=True)
                        if r >= 0:
                            times.setdefault((i, k), []).append(_child_cpu() - c0)
                            codes.setdefault((i, k), set()).add(p.returncode)
            warm = False
            med = {key: float(np.median(v)) for key, v in times.items()}
            diffs = []
            for i in range(1, len(roots)):
                for f in ("report.json", "model.json"):
                    diffs += [f"{f}{d}" for d in _same_numbers(json.loads((t / "dia0" / f).read_text()),
                                                               json.loads((t / f"dia{i}" / f).read_text()))]
            row = dict(seed=seed, label=label, expected=expected, roots=[str(x) for x in roots],
                       calibrate=[med[i, "calibrate"] for i in range(len(roots))],
                       diagnose=[med[i, "diagnose"] for i in range(len(roots))],
                       codes={f"{i}/{k}": sorted(v) for (i, k), v in codes.items()}, report_differences=diffs)
            rows.append(row)
            ratios = [d / c for d, c in zip(row["diagnose"], row["calibrate"])]
            print(f"== seed {seed} {label}: ipmc calibrate " + " / ".join(f"{x:.2f}" for x in row["calibrate"])
                  + " s CPU, ipmc diagnose " + " / ".join(f"{x:.2f}" for x in row["diagnose"])
                  + " s CPU: ratio " + " / ".join(f"{x:.1f}x" for x in ratios) + f" (exit {row['codes']})"
                  + ("" if len(roots) < 2 else
                     f"; reports {'the same, number by number' if not diffs else 'DIFFER: ' + '; '.join(diffs[:5])}"),
                  flush=True)
    return rows


def _print(r: dict) -> None:
    cw, cc = r["calibrate"]["wall"], r["calibrate"]["cpu"]
    dw, dc = r["diagnose"]["wall"], r["diagnose"]["cpu"]
    v = r["verdicts"]
    said = f"{v[0][0]} {list(v[0][1])}" + ("" if len(v) == 1 else f"  (VERDICT DIFFERS BETWEEN ROUNDS: {v})")
    print(f"\n== seed {r['seed']} {r['label']} (truth {r['expected']}) -> {said}")
    print(f"   calibrate: {cw:.3f} s wall, {cc:.3f} s CPU ({r['calibrate_evaluations']} parameter sets in "
          f"{r['calibrate_calls']} model calls)")
    print(f"   diagnose:  {dw:.2f} s wall, {dc:.2f} s CPU")
    print(f"   ratio diagnose/calibrate: {dw / cw:.0f}x wall, {dc / cc:.0f}x CPU")
    print("   stage        sets   calls  fits  points   wall s    CPU s")
    for s in STAGES:
        x = r["profile"].get(s)
        if x:
            print(f"   {s:<10} {x['sets']:>7} {x['calls']:>6} {x['fits']:>5} {x['points']:>7} {x['seconds']:>8.2f} "
                  f"{x['cpu_s']:>8.2f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default=CASES, help="seed:label,... of the independent generator")
    ap.add_argument("--rounds", type=int, default=3, help="interleaved rounds per case (median)")
    ap.add_argument("--commands", action="store_true",
                    help="time the ipmc commands (what the issue measured) instead of the library calls")
    ap.add_argument("--roots", default="",
                    help="with --commands: comma-separated checkouts to run the commands from, interleaved "
                         "(e.g. before,after); their reports are compared number by number")
    a = ap.parse_args(argv)
    print("command: python3 " + " ".join([os.path.relpath(__file__, ROOT)] + list(argv if argv is not None else sys.argv[1:])))
    if a.commands:
        roots = [Path(x).resolve() for x in a.roots.split(",") if x] or None
        rows = run_commands(a.cases, a.rounds, roots)
        for i, root in enumerate(roots or [ROOT]):
            ratios = [r["diagnose"][i] / r["calibrate"][i] for r in rows]
            print(f"\n{root}: ipmc diagnose / ipmc calibrate, CPU: median {np.median(ratios):.1f}x, "
                  f"max {max(ratios):.1f}x (goal <= 5x)" + ("" if max(ratios) <= 5 else
                                                             f"; above 5x: {', '.join(str(r['seed']) for r, x in zip(rows, ratios) if x > 5)}"))
        bad = [r["seed"] for r in rows if r["report_differences"]]
        if bad:
            print(f"reports differ between the roots on seeds {bad}", file=sys.stderr)
        return 0
    rows = run(a.cases, a.rounds)
    print("\nsummary (median over rounds): case, diagnose/calibrate CPU ratio, diagnose CPU s, calibrate CPU s")
    for r in rows:
        print(f"   {r['seed']} {r['label']:<32} {r['diagnose']['cpu'] / r['calibrate']['cpu']:>6.0f}x "
              f"{r['diagnose']['cpu']:>7.2f} {r['calibrate']['cpu']:>7.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
