/**
 * pfvi.h: the phase-fitted discrete Lagrangian integrator (O. T. Kosmas and
 * D. S. Vlachos, "Phase-fitted Discrete Lagrangian Integrators"; below K&V),
 * in layers that call only downward (docs/architecture.md):
 *
 *   pfvi_integrator.c  REBOUND glue: table, fields, options, the step entry,
 *                      the one place that reports errors
 *   pfvi_control.c     step control (K&V, "Frequency Evaluation and Error Control")
 *   pfvi_step.c        one trial/commit skeleton for every scheme
 *   pfvi_two_point.c,  the schemes: the two-point discrete Lagrangian
 *   pfvi_stages.c      (K&V section 3), the s-point one (K&V, "Increasing the
 *                      algebraic order")
 *   pfvi_solve.c       the s-point stage solve: Newton rounds with each body's
 *                      partner Jacobian, the two-body predictor, the stop rule
 *   pfvi_fitting.c     coefficients: fitted b, bbar, B, Bbar, normalisation, limiting u
 *   pfvi_lobatto.c     quadrature: the Gauss-Lobatto rule
 * and beside them
 *   pfvi_osculating.c  geometry: osculating circles, curvature frequency
 *   pfvi_centre.c      geometry: the centre and frequency of each harmonic model
 *   pfvi_state.c       scratch, forces, rollback, faults, the iteration rule
 *
 * Only symbols marked PFVI_API are exported from the library.
 */
#ifndef PFVI_H
#define PFVI_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include "rebound.h"

#define PFVI_API __attribute__((visibility("default")))
#define PFVI_INTERNAL __attribute__((visibility("hidden")))
// Four doubles as one value (GCC's and clang's vector extensions): loops over
// the stages written with them run in vector registers on any processor
// (two SSE2 halves, or one AVX2 register in a target clone). Each lane is
// the scalar operation on its own, rounded alike: the same bits either way.
// (PFVI_NO_CLONES builds the baseline path alone, without the AVX2 clones:
// tests/test_vector_paths.py compares the two builds' trajectories.)
typedef double pfvi_lanes __attribute__((vector_size(4*sizeof(double))));
// A comparison's result on lanes (all bits set where true), and yes in the
// lanes where the mask m is set, no elsewhere (a macro: a function returning
// vectors would change its ABI between the clones).
typedef long long pfvi_lane_mask __attribute__((vector_size(4*sizeof(long long))));
#define lanes_where(m, yes, no) ((pfvi_lanes)(((pfvi_lane_mask)(yes) & (m)) | ((pfvi_lane_mask)(no) & ~(m))))
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__) && !defined(PFVI_NO_CLONES)
#define PFVI_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define PFVI_VECTOR_CLONES
#endif

// A macro's value as a string, for the field documentation.
#define PFVI_STR_(x) #x
#define PFVI_STR(x) PFVI_STR_(x)
// (A list's text: PFVI_STR would read its commas as arguments.)
#define PFVI_STR_LIST_(...) #__VA_ARGS__
#define PFVI_STR_LIST(...) PFVI_STR_LIST_(__VA_ARGS__)

// Name under which the integrator is registered with REBOUND. Lower case:
// REBOUND's Python setter lower-cases integrator names.
#define PFVI_NAME "pfvi"

/* ---------------------------------------------------------------- options */

// Every option with a fixed set of values is one X-macro list: value, name,
// and meaning. The enum, REBOUND's enum descriptors (names in Python and in
// archives), validation and the allowed values named in errors all come
// from it (as rebound.h does with REB_GENERATE_ENUM_DESCRIPTORS).
#define PFVI_FITTINGS(X) \
    X(PFVI_FITTING_PHASE, 0, "phase")                  /* K&V's Ld divided by gamma(u): exact q and p on the oscillator */ \
    X(PFVI_FITTING_PHASE_LITERAL, 1, "phase-literal")  /* K&V's Ld as printed: momenta scaled by gamma(u) */ \
    X(PFVI_FITTING_NONE, 2, "none")                    /* classical Marsden-West Ld (velocity Verlet at s = 2) */ \
    X(PFVI_FITTING_EXACT, 3, "exact")                  /* "phase" with fitted interior columns: exact on the oscillator at every s */

#define PFVI_FREQUENCIES(X) \
    X(PFVI_FREQUENCY_CURVATURE, 0, "curvature")  /* K&V eq. (freq): omega = |v x a|/|v|^2, per particle */ \
    X(PFVI_FREQUENCY_FIXED, 1, "fixed")          /* the field omega, for every particle */ \
    X(PFVI_FREQUENCY_RADIAL, 2, "radial")        /* omega^2 = -a.d/|d|^2, d = q - centre: the harmonic part carries the central pull */ \
    X(PFVI_FREQUENCY_MEAN_MOTION, 3, "mean-motion") /* n of the osculating Kepler orbit about the partner */

// The centre the harmonic model of a particle refers to: the fitted
// interpolation is applied to d = q - c(t), c moving uniformly over the step.
#define PFVI_CENTRES(X) \
    X(PFVI_CENTRE_ORIGIN, 0, "origin")          /* K&V: the coordinate origin, at rest */ \
    X(PFVI_CENTRE_BARYCENTRE, 1, "barycentre")  /* the barycentre of the massive bodies */ \
    X(PFVI_CENTRE_PARTNER, 2, "partner")        /* the barycentre of the particle and its partner (the tightest pair, largest G (m + m_j) / r^3) */

#define PFVI_STEP_CONTROLS(X) \
    X(PFVI_STEP_CONTROL_SEED, 0, "seed")              /* accept/reject on the estimate, propose the next h */ \
    X(PFVI_STEP_CONTROL_REVERSIBLE, 1, "reversible")  /* h solves estimate(y_n, y_n+1) = epsilon */ \
    X(PFVI_STEP_CONTROL_SYMMETRIC, 2, "symmetric")    /* h = kappa/rho, rho the pairs' frequency tracked time-symmetrically: one solve per step */

#define PFVI_ENUM_VALUE(symbol, value, name) symbol = value,
enum pfvi_fitting { PFVI_FITTINGS(PFVI_ENUM_VALUE) };
enum pfvi_frequency { PFVI_FREQUENCIES(PFVI_ENUM_VALUE) };
enum pfvi_step_control { PFVI_STEP_CONTROLS(PFVI_ENUM_VALUE) };
enum pfvi_centre_kind { PFVI_CENTRES(PFVI_ENUM_VALUE) };
#undef PFVI_ENUM_VALUE

// Defaults and ranges.
#define PFVI_STAGES_MIN 2
#define PFVI_STAGES_MAX 8
#define PFVI_STAGES_DEFAULT 8
#define PFVI_U_MAX_DEFAULT 1.0
#define PFVI_EPSILON_DEFAULT 1e-6

/* -------------------------------------------------------------- constants */

// A step is refused when u lies within this distance (in cos u or sin u) of a
// pole of the two-point coefficients: cos u = 0 (all fitted modes) and
// sin u = 0 away from u = 0 (phase-literal, through gamma = u cot u); and
// when the s-stage matrix's determinant falls below this fraction of its
// value at u = 0.
#define PFVI_POLE_GUARD 1e-3
// A fixed frequency's step is refused as unstable once half the trace of its
// linear map exceeds 1 by this: a deviation growing by at most 1 + 1.4e-7
// per step (an e-fold in 7e6 steps) passes, and round-off in the trace
// (terms of order 1) cannot refuse a stable step.
#define PFVI_STABILITY_SLACK 1e-14
// Largest fitted frequency: the two-point step needs omega^2 (and omega^2 q),
// which leave the doubles above omega ~ 1.3e154. A larger omega (a body
// almost at rest turning sharply, or u_max/|dt| for a tiny dt) is fitted as 0,
// the classical scheme, and counted in n_u_limited.
#define PFVI_OMEGA_MAX 1e150
// Fixed-point iterations (the stage solve, and the two-point step's implicit
// final kick when forces depend on velocities): at most this many rounds;
// an iteration stops when the largest relative change is zero or no longer
// decreases, and has converged if that change is at most the tolerance.
#define PFVI_ITERATION_MAX 50
#define PFVI_ITERATION_TOLERANCE 1e-12
// The s-point stage solve's stop by its measured rate (pfvi_solve.c): once
// theta/(1 - theta) times the last correction (theta: its ratio to the one
// before) is below RESOLUTION (2^-52, relative), the corrected iterate gets
// one final round, whose change must be at most CONFIRM (2^-48) for it to
// be taken; otherwise the rounds go on.
#define PFVI_SOLVE_RESOLUTION 0x1p-52
#define PFVI_SOLVE_CONFIRM 0x1p-48
// Step control. Standard controller: next h = h * SAFETY * (epsilon/error)^(1/ORDER),
// the factor kept within [SHRINK_MIN, GROW_MAX]; ORDER is the measured order
// in h of the osculating-circle estimate (docs/adaptive.md).
#define PFVI_CONTROL_SAFETY 0.9
#define PFVI_CONTROL_ORDER 3.
#define PFVI_CONTROL_GROW_MAX 2.
#define PFVI_CONTROL_SHRINK_MIN 0.1
// Consecutive rejections of one step after which it is given up.
#define PFVI_CONTROL_MAX_REJECTIONS 60
// The reversible step: trial steps per step at most, and the tolerance on
// |F - 1| and on the relative change of the fitted frequencies at which the
// step equation counts as solved (raised to the estimate's round-off level).
#define PFVI_REVERSIBLE_MAX_TRIALS 40
#define PFVI_REVERSIBLE_TOLERANCE 1e-10
// The symmetric step (pfvi_control.c): h = kappa/rho, with rho tracking the
// step density sigma = (sum_i omega_i^K)^(1/K) of the pairs' frequencies
// omega_i^2 = G (m_i + m_partner)/r^3, and kappa = (epsilon/C_s)^(1/(2s - 2))
// (C_s: PFVI_SYMMETRIC_CONSTANTS, measured so that epsilon is about the
// relative position error per orbit at e = 0.5), at most KAPPA_MAX. The
// Newton stage solve converges far beyond it (with fixed steps at s = 8 in
// 3 to 5 rounds up to kappa 4 to 5, docs/solve.md), but above 1 the track's
// drift correction fires on Kepler orbits (measured, 200 orbits at s = 8:
// one asymmetric step at e >= 0.5 and kappa 1.16, 796 of 1394 steps at
// e = 0.7 and kappa 1.6), breaking the steps' time symmetry: the cap stays
// at 1 until the track holds there. Why it fires (issue 42, item 3,
// measured): no drift. The mismatch average of a Kepler track settles at an
// offset of its own, set by kappa, e and the phase the track started at
// (e = 0.7: -0.09 at kappa 1 from any phase but pericentre, +0.016 from
// pericentre; -0.13 at kappa 1.16, -0.21 at 1.4), and stays within 0.015 of
// it over 200 orbits; the correction measures it from 0 (at kappa 1 it
// already fires at e = 0.78 from a quarter of the orbit: 2 of 408 runs).
// Measured from the settled value instead (branches i42-kappa-base and
// i42-kappa-cap125), Kepler e = 0 ... 0.99 takes no asymmetric step up to
// kappa 1.37 at s = 4 ... 8; but at kappa > 1 reversals of multi-body runs
// fail with either correction (the compact five-planet system, 3000 steps
// and back: 0.4 AU off at kappa 1.05, 2.7e-3 AU at 1.163, no asymmetric
// step; a comet crossing Jupiter's orbit: new asymmetric steps on the way
// back), so the cap stays.
#define PFVI_DENSITY_NORM 8
// e^2 beyond which the eccentricity factor (1 - e^2)^(-gamma) is held
// (e = 0.999; unbound and radial pairs get it too): beyond it epsilon's
// meaning is not kept (the factor would reach 1000 at s = 2 by e = 0.99995).
#define PFVI_DENSITY_E2_MAX 0.998
// A term below this fraction of the largest so far is not computed: it
// would change sigma by less than its K-th power over K (0.3^8/8 = 8e-6).
#define PFVI_DENSITY_NEGLIGIBLE 0.3
#define PFVI_SYMMETRIC_CONSTANTS {0., 0., 14., 0.32, 0.019, 8.3e-4, 4.4e-5, 2.3e-6, 1.2e-7}
#define PFVI_SYMMETRIC_BETA {0., 0., 1.5, 2.2, 2.5, 3.0, 3.4, 3.8, 4.2}
#define PFVI_KAPPA_MAX 1.0
// Epsilon below which the symmetric control's error per orbit stops
// falling (round-off; measured, Kepler e = 0.5, 10 orbits): a smaller
// request is taken as this, per s. (Above C_s KAPPA_MAX^(2s - 2) kappa is
// held at KAPPA_MAX: requests there take its steps.)
#define PFVI_EPSILON_FLOORS {0., 0., 1e-10, 1e-12, 1e-13, 1e-14, 1e-14, 1e-14, 1e-14}
// Below this kappa REBOUND is told, once per simulation, how many steps an
// orbit takes: about 2 pi/kappa on a circle (measured 1.09 times it), more
// on eccentric orbits (s = 2 at epsilon 1e-10: 2.6e6 steps an orbit at
// e = 0, 7e7 at e = 0.9), which a user takes for a hang where more stages
// take tens. Only s = 2 below epsilon 1.4e-7 gets there (s = 3 at its floor:
// kappa 1.3e-3).
#define PFVI_KAPPA_WARN 1e-4
// A symmetric step at whose end the density sigma exceeds this many times the
// one it was sized for (kappa/h) is retried at half the step.
#define PFVI_DENSITY_JUMP_MAX 3.0
// A whole interval whose density at an end exceeds SPLIT_DENSITY times the
// one it was sized for, and whose stages resolve the forces worse than
// SPLIT_RESOLUTION times the Kepler worst (u/(RESOLUTION_s kappa)), is
// crossed in two halves (pfvi_control.c; time-symmetric). The Encke-like
// comet among the inner planets (benchmarks/comet_steps.py) falls in from
// where Venus's term sets the density: its own term rises threefold within
// one step, and that step's error, a kick in the comet's energy that the
// way out does not undo, set the run's error (up to 36 epsilon a n over 8
// starting phases and 6 epsilon; now at most 4.2). Along Kepler orbits
// (e = 0.5 ... 0.999, four phases, s = 8, epsilon 1e-7 ... 1e-10) the
// density at an end stays below 1.9 kappa/h and nothing is split; at 1.8
// up to 15% of the steps of e = 0.85 were.
#define PFVI_SPLIT_DENSITY 1.9
#define PFVI_SPLIT_RESOLUTION 0.85
// Below this total mass a pair's barycentre is formed from mass fractions
// m_i/M, not m_i x_i/M: the products underflow (issue 40: two masses of
// 1e-310 at 1e-100 had it at 0 and moved by half their separation in one
// step). Above it the products are kept, so that every trajectory stays
// bit-identical.
#define PFVI_MASS_TINY 1e-150
// An adaptive step below the rounding of t is blamed on the tightest pair
// (point masses colliding) when that pair's time scale 1/omega is within
// 1/this of t's rounding: omega |t| DBL_EPSILON above it (issue 40: two point
// masses falling together stopped at 0.5 there, and were told to use a larger dt).
#define PFVI_TIGHT_PAIR_ROUNDING 1e-3
// Members of the subsystem a body's Kepler term refers to, at most (the
// partner and what it is bound to more tightly: pfvi_timescales.c).
#define PFVI_SUBSYSTEM_MAX 8
// An encounter term is nu_cr (1 + c cos^2 theta) (theta between the pair's
// r and v): c (pfvi_timescales.c).
#define PFVI_ENCOUNTER_APPROACH 1.0
// The encounter term of a pair that is neither body's partner is weighted
// by (R/(1 + R))^(1/(2s - 2)), R the pair's pull on each body against its
// partner's (summed over the two bodies): the error an unresolved pull leaves
// scales with it. Two planets about a star (Jupiter and Saturn: R ~ 5e-3)
// had encounter terms as large as Jupiter's orbit term, which made the
// density beat at their synodic period; the track's drift from it took 67
// corrections (asymmetric steps) over 1e4 Jupiter orbits of the outer solar
// system and the energy error grew 12-fold (docs/roundoff.md). 0: unweighted.
#define PFVI_ENCOUNTER_WEIGHTED 1
// The weight's crossing term X^p (pfvi_timescales.c, encounter_weight): a
// pair crossing faster than its bodies orbit (X = nu_cr^2/(G (S_i + S_j)) > 1)
// is weighted towards 1. Weighted by its pull alone, a retrograde body inside
// Jupiter's orbit (R ~ 1e-3, X ~ 2 at conjunction) was given steps longer than
// the passage and ended up to 1e4 epsilon a n off at s = 8 (issue 40). p = 4
// keeps planetary pairs' weights (X ~ 0.1: the compact five-planet system
// takes no asymmetric step over 1e4 orbits, 2.5% more steps); p = 2 broke
// that (2 asymmetric steps in its first 500).
#define PFVI_ENCOUNTER_FAST_POWER 4
// The a posteriori check of a symmetric step: its stages resolve each
// particle's acceleration to u = ((s - 1)! |D|/A)^(1/(s - 1)) (D the leading
// coefficient of their polynomial, A the largest |a|), about h times the
// particle's fastest time scale. Along Kepler orbits of e = 0 ... 0.9999,
// from any phase, two bodies or a test particle, u <= RESOLUTION_s kappa
// (measured: 1.02, 1.42, 1.86, 2.27, 2.67, 3.06, 3.46 for s = 2 ... 8,
// each raised by 5%). A step whose stages imply an
// error (u/(RESOLUTION_s kappa))^(2s - 2) above RESOLUTION_MAX is retaken
// shorter (at most RESOLUTION_RETRIES times, each at most half the last)
// and the density scaled up
// (lambda, density_scale) by the factor it took; lambda falls back towards
// 1 where the stages resolve whole intervals RESOLUTION_SLACK times finer
// than needed.
#define PFVI_RESOLUTION_CONSTANTS {0., 0., 1.1, 1.5, 1.95, 2.4, 2.8, 3.2, 3.65}
#define PFVI_RESOLUTION_MAX 3.
// The resolution check also measures the pulls on a body beyond its
// partner's against their own size (pfvi_step.c, issue 40): a weak pull that
// varies within the step (a retrograde body passing Jupiter at 2 AU, 1e-3 of
// the Sun's pull) leaves an error proportional to its size, which against the
// net acceleration read sqrt(F/A) times too fine. That error is a kick at each
// passage, not the time-symmetric phase error of a Kepler orbit: its energy
// error shears along the orbit (measured: 374 steps whose local errors summed
// to 1.25e-6 AU ended 3.7e-4 AU off after 58 orbits). So it is held this many
// times below the Kepler level (benchmarks/retrograde_sweep.py: 1 left 8 of
// 240 runs at s = 8 above the goal of 10, 10 none, 100 twice the asymmetric
// steps for no run over the goal).
#define PFVI_WEAK_PULL_MARGIN 10.
#define PFVI_RESOLUTION_RETRIES 5
#define PFVI_RESOLUTION_SLACK 2.0
// Without pairs (no density to track: pfvi_control.c, control_unpaired)
// each step's resolution u is aimed at AIMS_s kappa for s stages (a circular
// orbit's steps under the density have u = kappa), proposed SAFETY times
// below that, and a step above RETAKE times the aim is retaken. Measured on
// test particles in a Kepler potential from additional_forces (e = 0 ...
// 0.99, epsilon 1e-6 ... 1e-10, s = 8; tests/test_unpaired.py): an aim of 1
// took 1.3-2.5 times the steps of the same orbits about a massive body, for
// errors 1e3 times smaller; 1.4 with RETAKE 1.25 ends within the paired
// runs' errors; 1.8 left e = 0.99 from pericentre 5e-7 off at epsilon 1e-7
// and 1e-8 alike. Fewer stages see less of a pericentre passage in their
// top coefficient (degree s - 1). 3 orbits from pericentre and apocentre,
// e = 0 ... 0.999, epsilon 1e-6, 1e-9 and 1e-12 (benchmarks/unpaired.py
// --stages, 2026-11-28): at 1.4, e = 0.99 ended 7 epsilon per orbit off at
// s = 2 and 64-88 at s = 3, where the paired runs end within 1 and 0.6;
// 0.55 and 0.45 bring them to 1 and 0.9-1.1, in 2.5 and 3.1 times the
// steps, still fewer than the paired runs take. At s = 4 and 5, 1.4 left
// e = 0.99 15-19 epsilon per orbit off at 1e-6 (1.4-5.4 at 1e-9), and C-infinity
// bumps were kept unresolved thousands of times (the stages' u stopped
// falling with the step); 0.8 and 1.0 bring e = 0.99 to 0.41 and 0.36
// (e = 0.999: 11 and 9.7) in 1.8 and 1.4 times the steps, and the bumps'
// unresolved steps from 8452 to 88 (three bodies, four bumps, s = 4,
// epsilon 1e-10; docs/adaptive.md).
#define PFVI_UNPAIRED_AIMS_2_TO_8 0.55, 0.45, 0.8, 1.0, 1.4, 1.4, 1.4
#define PFVI_UNPAIRED_AIMS {0., 0., PFVI_UNPAIRED_AIMS_2_TO_8}
#define PFVI_UNPAIRED_SAFETY 0.9
#define PFVI_UNPAIRED_RETAKE 1.25
// A retake that lowered u below this fraction of the last is still helping.
#define PFVI_UNPAIRED_HELPING 0.9
// A retake that ends below this fraction of the aim left behind what made
// the first trial coarse: a force that jumps there would be approached in
// ever shorter steps (sim.dt 0.001 ended in a step of 3e-16 and a refusal at
// a jump of the force at r = 1.5); after RESOLUTION_RETRIES such steps in a
// row the next coarse first trial is kept, unresolved.
#define PFVI_UNPAIRED_SUSPECT 0.2
// Fixed steps (epsilon = 0) are checked as the symmetric steps are: the
// error per orbit their stages imply (pfvi_resolution_error; for a fitted
// step from the residual its fitted path does not carry). Above FIXED_WARN
// REBOUND warns, once per simulation. That estimate is bounded (the leading
// coefficient of s stage values is at most sum |w_k| times the largest; at
// s = 8 it stays below 0.01 however long the step), and at s = 2 it runs 5 to
// 25 times above the error measured on Kepler orbits: so a step is refused
// not on it but on the density sigma of the symmetric control at the step's
// two ends, measured (O(N N_active), twice) only where the stages' u exceeds
// FIXED_GATE times the largest u stage values can give: |h| sigma above
// FIXED_KAPPA_MAX is about an orbit of the fastest time scale per step
// (measured on Kepler orbits, e = 0 ... 0.9, s = 4 ... 8: every step accepted
// beyond it ended at least 0.3 of the orbit off within three steps).
#define PFVI_FIXED_WARN 1e-2
// Where the stages' estimate saturates (u above FIXED_GATE of its bound) it
// is no measure: a step of the density's |h| sigma above the kappa at which
// the symmetric control's steps err by FIXED_WARN per orbit, (FIXED_WARN/
// C_s)^(1/(2s - 2)), warns too, and without pairs (no density) the
// saturation itself does. Before, Kepler e = 0.9 at sim.dt = 0.1 (5.7
// radians at pericentre; the stages said 1.1e-3 per orbit) lost 14% of its
// semi-major axis in 10 orbits, and a test particle in a Kepler potential
// from additional_forces ended 170 off at sim.dt = 1, without a word.
#define PFVI_FIXED_GATE 0.4
#define PFVI_FIXED_KAPPA_MAX 6.3
// The track's rho follows lambda sigma to within the lag of its update:
// measured over every scene of benchmarks/step_control.py (s = 4 and 8,
// epsilon 1e-6 and 1e-10), rho/(lambda sigma) lay in [0.30, 2.28]. The
// update keeps that ratio (rho tracks any constant times sigma), so a rho
// stored outside [1/TRACK_RATIO_MAX, TRACK_RATIO_MAX] lambda sigma (set by
// hand, or an edited archive) would never come back: the track starts afresh.
#define PFVI_TRACK_RATIO_MAX 16.
// The track integrates the density's rate, so what it misses of sigma's
// change over a step (the quadrature error of its update, large where a step
// is a sizeable part of an orbit) stays in rho: on one Kepler orbit it comes
// back within the orbit, but where sigma has several frequencies (a planetary
// system) it wanders, a random walk of log(rho/sigma): measured on the outer
// solar system at epsilon 1e-6, rho/sigma drifted to 0.45 within 6000 yr, and
// the energy error went from 3e-11 to 9e-8 with the member of an ensemble
// (docs/roundoff.md). So each full interval's mismatch m = log(rho/(lambda
// (sigma_start sigma_end)^(1/2))) is averaged, with weight TRACK_MISMATCH_WEIGHT
// per interval, and where the average leaves +-TRACK_MISMATCH_MAX rho is moved
// back onto lambda sigma by it (a step that is not time-symmetric: counted in
// n_asymmetric). On Kepler orbits the average stays within 0.025 (measured,
// e = 0.5 ... 0.99, epsilon 1e-6 and 1e-12): the correction does not fire.
// The wander on planetary systems came from the planets' mutual encounter
// terms (PFVI_ENCOUNTER_WEIGHTED): weighted, the average stays within 0.005
// on the outer solar system over 1e4 Jupiter orbits (no correction) and
// within 0.1 on a compact five-planet system (about one correction per 1e3
// orbits). Spreading the correction over many intervals made the energy
// error grow faster (it is asymmetric every interval it acts), and a
// time-symmetric spring on the mismatch was unstable (docs/roundoff.md).
// A t_compensation beyond this fraction of max(1, |t|) is not t's rounding
// (folded every step, it stays below half of t's last place; archives
// written before the fold carried up to 1e-9 |t| after 1e7 held steps):
// set by hand or an edited archive, it is dropped.
#define PFVI_T_LO_MAX 1e-9
// A fresh track starts on the curve the track begun at the leading orbit's
// last pericentre (rho = lambda sigma there) follows (pfvi_control.c,
// pericentre_start), at a grid point at the state as before, where the
// other density terms are a small part: (sigma/term)^8 <= TRACK_START_SHARE
// (the leading pair counts 2). The start lambda sigma + kappa g/2 put a
// track begun away from pericentre on a curve about 8% below the density
// (the mismatch average near -0.09 from apocentre, +0.01 from pericentre),
// swinging about it over many orbits, and where an orbit then took close
// to a whole number of steps the orbits' errors added up (benchmarks/
// commensurate_steps.py --sweep; docs/step-control.md, "Where a track
// starts"). Below TRACK_START_E the two starts differ little and the
// errors are far below epsilon (the fitting carries a circle exactly); an
// orbit of more than about TRACK_START_STEPS steps (s = 2 ... 4, or epsilon
// far below 1e-10) is not run, as the errors there do not add up (and at s =
// 2 with an edit every other step the emulation cost 100 times the step).
#define PFVI_TRACK_START_SHARE 3.
#define PFVI_TRACK_START_E 0.1
#define PFVI_TRACK_START_STEPS 64
#define PFVI_TRACK_MISMATCH_WEIGHT (1./32.)
#define PFVI_TRACK_MISMATCH_MAX 0.1
// The steady track (pfvi_control.c, docs/roundoff.md): with three or more
// bodies, where the density at the ends of STEADY_WINDOW intervals in a row,
// spanning at least 2 pi/sqrt(G (m_i + m_j)/r^3) of the loosest partner pair
// seen (a full cycle of the slowest orbit: a comet's long quiet arc about
// its aphelion is not steady), stayed within a factor 1 + STEADY_BAND, rho
// is held as it is once it reaches the largest of them (no jump: the track
// overshoots the density's peaks) and the steps are constant:
// the classical step is symplectic, and the energy of a planetary system
// stays bounded, which the varying steps of the track did not give (a
// time-symmetric track is not symplectic: over 1e5 Jupiter orbits the outer
// solar system's energy error grew as t^0.4 ... t^1.45 with no asymmetric
// step; constant steps of the same mean length kept it within 0.9 of its
// first tenth). The hold ends where lambda sigma at an interval's end leaves
// [rho/(1 + STEADY_BAND), rho (1 + STEADY_EXCESS)] (a step up to 2% longer
// than the density asks: at most 1.02^(2s - 2) = 1.3 times its error):
// above, the track goes on from rho as it is (the density's rate takes it
// up); below, rho is set to lambda sigma (a jump: n_asymmetric).
#define PFVI_STEADY_WINDOW 64
#define PFVI_STEADY_BAND 0.25
#define PFVI_STEADY_EXCESS 0.02
#define PFVI_STEADY_BODIES 3
// Outputs (pfvi_output.c): a requested time within OUTPUT_NEAR of the run's
// state, relative to the time the run has spanned, plus OUTPUT_NEAR_ULPS of
// t's last places, is that state's: shown as it is, with no new step and no
// output step. A reversal comes back to its start with t off by the steps'
// rounding (1.4e-11 after 2600 steps at e = 0.95, the state within 1e-13 of
// the start): a new step there and an output step back left integrate(400)
// and back 8.5e-11 AU off instead. Not relative to |t| itself (REBOUND's
// tolerance for its last step, 1e-12 of t): a run from t = 1e10 showed a
// state 0.005 before the requested time as that time's (a hostile trial:
// 0.017 off IAS15 on Kepler e = 0.9).
#define PFVI_OUTPUT_NEAR 1e-12
#define PFVI_OUTPUT_NEAR_ULPS 2.
// Variational particles found scaled by one factor since an output (REBOUND
// rescales them past 1e100) within this relative slack are taken as
// rescaled, not edited: the run's are scaled alike.
#define PFVI_OUTPUT_RESCALE_SLACK 1e-14
// lambda (density_scale) at most: steps 1e12 times shorter than the density
// asks are no time scale a REBOUND run resolves; a stored value above it is
// discarded, and the retakes never raise lambda past it.
#define PFVI_DENSITY_SCALE_MAX 1e12
// REBOUND's sim.dt of a new simulation (reb_simulation_create): not taken
// as a cap on the first step of the symmetric control.
#define PFVI_REBOUND_DT_DEFAULT 0.001
// A stage predictor extrapolates the last step's stages over at most this
// many of its lengths; beyond, the first iterate is the start state's
// Taylor path (a step after a much shorter one: a capped step).
#define PFVI_PREDICTOR_RATIO_MAX 2.0
// Newton iterations on Kepler's equation per stage point of the two-body
// predictor, at most (the Taylor path if it does not converge).
#define PFVI_PREDICTOR_KEPLER_ITERATIONS 30
// A Halley correction of at most this (relative) is the last: Halley's next
// would be of its cube, below 1e-12, and the
// orbit's functions are carried to the corrected anomaly by their Taylor
// series (to its cube) instead of evaluated there again.
#define PFVI_PREDICTOR_KEPLER_LAST 1e-4
// Stumpff's functions c_n(x) by their series to x^6 where |x| is below this
// (below 1e-16 relative); the predictor reaches each stage from the last by
// the addition theorems wherever the stretch between them has |x| below it.
#define PFVI_STUMPFF_SERIES 0.1

// Contacts inside a step (pfvi_contact.c, docs/collisions.md): with
// collisions on and a radius set, or sim.exit_min_distance set, each step
// taken is searched for the first time a pair's separation falls below the
// sum of their radii or exit_min_distance, along the polynomial of degree
// 2s through the step's positions and accelerations at its s nodes (the mean
// of those through the velocity at either end), and the step is retaken to
// end there.
// Samples of that polynomial per candidate pair and step (between samples, a
// dip is found by refining each sampled minimum):
#define PFVI_CONTACT_SAMPLES 64
// The retaken step ends where the path is this far inside the limit
// (relative to the limit; at most half the dip's depth), so that REBOUND's
// check at the step's end sees the overlap, still approaching:
#define PFVI_CONTACT_DEPTH 1e-9
// A body's path over a step lies within its nodes' spread plus this many
// times |a|_max (h dc_max)^2/8 (the chord's sag between nodes) of the
// midpoint of its ends: the bound that selects candidate pairs.
#define PFVI_CONTACT_BOUND_SAFETY 4.
// After this many consecutive steps retaken at a contact their end did not
// reach (the path's contact and the step's disagree: a separation within the
// step's error of the limit), the steps are kept as taken until no contact is
// predicted (n_contact_kept).
#define PFVI_CONTACT_RETAKES 4
// sim.collision 'line' and 'linetree': REBOUND searches straight segments
// drawn back from each step's end over dt_last_done, which pfvi's long curved
// steps do not follow. A step whose segments meet where its path does not is
// retaken at half its length, at most this many times, until they agree:
#define PFVI_CONTACT_LINE_HALVINGS 40


/* ---------------------------------------------------- quadrature (lobatto) */

// Gauss-Lobatto quadrature on [0, 1] (K&V section 3, maximal order): nodes
// c^1 = 0 < ... < c^s = 1, weights w_j with sum_j w_j (c^j)^l = 1/(l+1) for
// l <= 2s - 3, and the differentiation matrix of the interpolating polynomial,
// a[k][j] = l_j'(c^k), with sum_j a^k_j = 0 and sum_j a^k_j (c^j)^n = n (c^k)^(n-1)
// (K&V, "Increasing the algebraic order"). Computed, not tabulated.
struct pfvi_lobatto {
    int s;
    double c[PFVI_STAGES_MAX];
    double w[PFVI_STAGES_MAX];
    double a[PFVI_STAGES_MAX][PFVI_STAGES_MAX];
    double lagrange[PFVI_STAGES_MAX]; // barycentric weights 1/prod_(m != j) (c^j - c^m): l_j(t) = lagrange[j] prod_(m != j) (t - c^m)
    // The classical step (u = 0) as the Runge-Kutta-Nystrom method it is
    // (Lobatto IIIA-IIIB: the classical discrete Lagrangian), with stage
    // positions Q^i = q_k + c_nu[i] h v_k + h sum_j nu[i][j] (h w_j) A^j.
    // nu = abar/w (abar = IIIA IIIB) in units of the weights, as IRKGL16
    // stores Gauss's; c_nu and nu are multiples of 2^-50, rounded so that
    // the identities the method's symplecticity (nu[i][j] - nu[j][i] =
    // c_nu[i] - c_nu[j], nu[s-1][j] = 1 - c_nu[j]) and symmetry (c_nu[s-1-i]
    // = 1 - c_nu[i], nu[s-1-i][s-1-j] = nu[i][j] + c_nu[j] - c_nu[i]) rest
    // on hold exactly in doubles: the map the doubles define is symplectic
    // and symmetric, so round-off cannot make it drift (docs/roundoff.md).
    // mu_hat (IIIB over the weights) gives the stage velocities V^i = v_k +
    // sum_j mu_hat[i][j] (h w_j) A^j for forces that depend on velocities.
    double c_nu[PFVI_STAGES_MAX];
    double nu[PFVI_STAGES_MAX][PFVI_STAGES_MAX];
    double nu_t[PFVI_STAGES_MAX][PFVI_STAGES_MAX];   // nu transposed (nu_t[j][i] = nu[i][j]): rows as vector lanes
    double mu_hat[PFVI_STAGES_MAX][PFVI_STAGES_MAX];
    double det_classical;   // determinant of the stage matrix at u = 0 (singularity guard), set by pfvi_fitting.c
};
PFVI_INTERNAL int pfvi_lobatto_compute(int s, struct pfvi_lobatto* rule);
// The s Lagrange basis polynomials of the rule's nodes at tau: l[m] = l_m(tau).
PFVI_INTERNAL void pfvi_lagrange_at(const struct pfvi_lobatto* rule, double tau, double* l);

/* --------------------------------------------------- coefficients (fitting) */

enum pfvi_fit_status { PFVI_FIT_OK = 0, PFVI_FIT_LIMITED = 1, PFVI_FIT_POLE = -1 };

// The two-point phase-fitted discrete Lagrangian of one particle over one
// step, in the form in which its position-momentum equations are solved:
// kick with the residual force, rotate with the harmonic flow at omega,
// kick again (docs/method.md derives it from K&V's b, bbar, B, Bbar).
struct pfvi_two_point_fit {
    double omega;        // fitted frequency after limiting
    double keep;         // 1 if cos u > 0, else cos u: q1 = keep q + ((cos u - keep) q + ...)
    double cos_u_m_keep; // cos(u) - keep, computed without cancellation
    double h_sinc_u;     // h sin(u)/u  (= sin(u)/omega)
    double omega_sin_u;  // omega sin(u)
    double half_kick;    // (h/2) tan(u)/u: weight of the residual force a + omega^2 q
    double gamma;        // phase-literal: gamma(u) = u cot u, its momentum scale; otherwise 1
};

// One particle's s-stage discrete Lagrangian over one step, u = omega h: the
// fitted interpolation of K&V (b, bbar, B, Bbar at every node), written
// with the cancellation-free combinations beta_m = b + bbar - 1 and beta_d =
// B + Bbar, the momentum normalisation G, and the LU factors of the matrix of
// the linear (kinetic) part of the equations p_k = -D1 Ld, dLd/d(delta q^j) = 0
// in the unknowns (q_k+1 - q_k, delta q^2, ..., delta q^s-1).
struct pfvi_stage_fit {
    double omega;
    // 1 at u = 0: the step is taken in the rule's Runge-Kutta-Nystrom form
    // (struct pfvi_lobatto, nu), not through the stage matrix below.
    int classical;
    double G;                         // -D1 Ld_printed = G p_k: gamma_s(u) for "phase" and "exact", else 1
    double u2;                        // "exact": u^2, the harmonic part solved with the linear part; else 0
    // The differentiation matrix of the interpolation, a[k][l] = psi_l'(c^k):
    // the rule's for "none", "phase" and "phase-literal"; for "exact" its
    // interior columns corrected so that the stationarity equations of the
    // delta q^j hold on the oscillator's exact path (pfvi_fitting.c).
    double a[PFVI_STAGES_MAX][PFVI_STAGES_MAX];
    double b[PFVI_STAGES_MAX];
    double bbar[PFVI_STAGES_MAX];
    double B[PFVI_STAGES_MAX];
    double Bbar[PFVI_STAGES_MAX];
    double beta_m[PFVI_STAGES_MAX];
    double beta_d[PFVI_STAGES_MAX];
    double q0_row[PFVI_STAGES_MAX-1]; // coefficient of q_k in each equation
    double lu[PFVI_STAGES_MAX-1][PFVI_STAGES_MAX-1];
    int pivot[PFVI_STAGES_MAX-1];
    // The matrix's inverse applied to the force weights: unknown l changes by
    // -solve[l][k] per unit of the force carried at stage k. Zero beyond s
    // stages and s - 1 unknowns, so that a round loops over fixed bounds.
    double solve[PFVI_STAGES_MAX-1][PFVI_STAGES_MAX];
    // The matrix's inverse applied to the start terms: the unknowns for zero
    // force are -(G h w_k) start_momentum - d_k start_offset, per component.
    double start_momentum[PFVI_STAGES_MAX-1];
    double start_offset[PFVI_STAGES_MAX-1];
};

// |u| = |omega h| above u_max is limited to u_max (omega reduced to match);
// omega above PFVI_OMEGA_MAX is fitted as 0.
PFVI_INTERNAL enum pfvi_fit_status pfvi_limit_u(double* omega, double h, double u_max, double* u);
PFVI_INTERNAL enum pfvi_fit_status pfvi_two_point_fit(double omega, double h, double u_max,
        int literal, struct pfvi_two_point_fit* fit);
// The stage coefficients at u (u = 0: classical) with the factorised stage
// matrix; *det is its determinant. Used at u = 0 to set rule->det_classical.
PFVI_INTERNAL void pfvi_stage_fit_at(const struct pfvi_lobatto* rule, double u, int fitting,
        struct pfvi_stage_fit* fit, double* det);
PFVI_INTERNAL enum pfvi_fit_status pfvi_stage_fit(const struct pfvi_lobatto* rule, double omega, double h,
        double u_max, int fitting, struct pfvi_stage_fit* fit);
// Solves the fit's factorised m x m system in place (b: m values).
PFVI_INTERNAL void pfvi_stage_solve(const struct pfvi_stage_fit* fit, int m, double* b);
// The s-point rule with its det_classical: what pfvi_stage_fit needs; and,
// if classical is not NULL, the fit at u = 0 (every fitting's, whatever h).
PFVI_INTERNAL int pfvi_stage_rule(int s, struct pfvi_lobatto* rule, struct pfvi_stage_fit* classical);
// Inspection from Python (tests, docs): the seed's printed coefficients, gamma,
// the two-point step's coefficients, the rule, and the stage coefficients.
PFVI_API void pfvi_seed_coefficients(double u, double c, double out[4]);
PFVI_API double pfvi_gamma(double u);
PFVI_API int pfvi_two_point_coefficients(double omega, double h, double u_max, int literal, double out[6]);
PFVI_API int pfvi_lobatto_table(int s, double* c, double* w, double* a);
// The classical form's c_nu (s), nu (s x s) and mu_hat (s x s), row by row.
PFVI_API int pfvi_nystrom_table(int s, double* c_nu, double* nu, double* mu_hat);
PFVI_API int pfvi_stage_coefficients(int s, double u, double* out);
// The differentiation matrix (s x s, row-major) of fitting `fitting` at u.
PFVI_API int pfvi_stage_differentiation(int s, double u, int fitting, double* out);

/* ------------------------------------------------ geometry (osculating) */

// The curvature of a path with velocity v and acceleration a, from v and a
// scaled by powers of two, so that no intermediate over- or underflows:
// omega = |v x a|/|v|^2, R = |v|^3/|v x a| (each may still be 0 or Inf where
// the true value lies outside the doubles), and the unit normal (towards the
// centre) and binormal. Returns 0, with omega = 0 and R = Inf, at rest or on
// a straight line.
struct pfvi_curvature {
    double omega;
    double R;
    double normal[3];
    double binormal[3];
};
PFVI_INTERNAL int pfvi_curvature_scaled(const double v[3], const double a[3], struct pfvi_curvature* k);
// K&V eq. (freq): the angular rate on the osculating circle.
PFVI_INTERNAL double pfvi_curvature_frequency(const double v[3], const double a[3]);

// The osculating circle of one particle at one point of its path: radius R
// and centre O = x + offset. defined = 0 on a straight line or at rest,
// where the curvature vanishes.
struct pfvi_osculating {
    double R;
    double offset[3];
    double binormal[3];  // (v x a) / |v x a|: the normal of the circle's plane
    double omega;        // |v x a| / |v|^2, the curvature frequency
    int defined;
};
PFVI_INTERNAL void pfvi_osculating_circle(const double v[3], const double a[3], struct pfvi_osculating* c);
// Whether the circles at a step's two ends bound anything (both defined, on
// the same side of the path: not across an inflection).
PFVI_INTERNAL int pfvi_osculating_comparable(const struct pfvi_osculating* c0, const struct pfvi_osculating* c1);
// K&V's bound | |R1 - R2| - |O1 - O2| | on the position error of a step from
// x0 to x1, relative to min(R1, R2), less its round-off level *noise (never < 0).
PFVI_INTERNAL double pfvi_osculating_error(const double x0[3], const struct pfvi_osculating* c0,
        const double x1[3], const struct pfvi_osculating* c1, double* noise);

/* ----------------------------------------------------------------- state */

// One particle's part of the stage equations that a step's rounds share:
// its start, the unknowns at zero force, and the parts of the stage points
// that do not depend on the unknowns.
// The linear structure of one particle's stage equations, as the solve
// sees them (pfvi_solve.c): R(y) = y - yc + S F(x(y)) with the stage points
// x_k = base_k + sum_l X[k][l] y_l and F_k = fscale a_k (+ u2 d_k); stages
// 1 .. k_last carry forces that act within the step; y[increment] is the
// step's position increment (the change is measured relative to it).
struct pfvi_solve_form {
    int classical;      // the classical form: X the shift x_k = q_k + y[k-1], k_last = s - 2
    int m;
    int k_last;
    int increment;
    double fscale;
    double u2;
    double S[PFVI_STAGES_MAX-1][PFVI_STAGES_MAX];
    double X[PFVI_STAGES_MAX][PFVI_STAGES_MAX-1];
};
// One body's Newton correction (pfvi_solve.c): NONE takes the plain round;
// SINGLE is corrected with its partner's pull, after its partner; PAIR
// corrects a pair of mutual partners in their relative coordinate (MEMBER:
// the pair's other body, done with it).
enum { PFVI_NEWTON_NONE = 0, PFVI_NEWTON_SINGLE = 1, PFVI_NEWTON_PAIR = 2, PFVI_NEWTON_MEMBER = 3 };
struct pfvi_newton {
    int kind;
    size_t partner;
    size_t companion;   // SINGLE about a pair's barycentre: the partner's partner (else SIZE_MAX)
    int mc;                        // the unknowns the step's forces depend on (the leading ones)
    double P[PFVI_STAGES_MAX][PFVI_STAGES_MAX];   // LU of I + S diag(g) X over them
    int Pperm[PFVI_STAGES_MAX];                   // its rows' order (row k: row Pperm[k])
    double Pinv[PFVI_STAGES_MAX];                 // its pivots' reciprocals
    double Q[PFVI_STAGES_MAX-1][PFVI_STAGES_MAX]; // P^-1 S
    double C[PFVI_STAGES_MAX][PFVI_STAGES_MAX];   // LU of Woodbury's capacitance matrix
    int Cperm[PFVI_STAGES_MAX];
    double Cinv[PFVI_STAGES_MAX];
    double n[PFVI_STAGES_MAX][3];  // direction from the partner at each stage (softened length)
    double d[PFVI_STAGES_MAX];     // the rank-one weight 3 fscale alpha_k
    double gc[PFVI_STAGES_MAX];    // the isotropic part -fscale alpha_k
};

struct pfvi_stage_start {
    double q0[3];
    double v0[3];                        // the start velocity (the classical form's)
    double d0[3];                        // q0 - centre
    double yc[PFVI_STAGES_MAX-1][3];     // L^-1 g: the unknowns if no force acted (zero beyond s - 1)
    double base[PFVI_STAGES_MAX][3];     // beta_m^k d0 (interior k)
    double shift[PFVI_STAGES_MAX][3];    // the centre's displacement c^k h after the start
};


struct pfvi_options {
    int fitting;
    int frequency;
    int stages;
    double omega;
    double u_max;
    double epsilon;
    int step_control;
    int centre;
};

// What the next step needs of the last one: position and velocity (compared
// bitwise, in the order of struct reb_particle), mass, and the acceleration.
struct pfvi_end_state {
    double xv[6];
    double m;
    double a[3];
};

// A particle's position, velocity and mass, as an output keeps them
// (pfvi_output.c; saved in archives).
struct pfvi_output_particle {
    double xv[6];
    double m;
    double a[3];  // the run's state: the acceleration the next step starts from
};

// What else an output was shown with, per particle (pfvi_output_is_shown,
// pfvi_output_forces_hold): its radius (a contact search the run's step past
// the output did not make), and, with velocity-dependent forces pfvi cannot
// see into, the forces at the run's state as evaluated when the output was
// shown (the kept a[] is the end stage's, at the stage velocity).
struct pfvi_output_check {
    double a_seen[3];
    double radius;
};

/* ------------------------------------------- geometry (time scales) */

// What the time scales see of REBOUND's gravity: G (0 without gravity), the
// softening, which bodies attract (index < N_active, m > 0), and the ghost
// boxes the force sums over (position and velocity shifts of an image; the
// box itself first, and image n_images - 1 - g mirrors image g).
// Four particles' coordinates, velocities and masses as vector lanes, for
// the pair scans of pfvi_timescales.c (doubles: realloc's alignment).
struct pfvi_lanes_block {
    double x[4], y[4], z[4], vx[4], vy[4], vz[4], m[4];
};

struct pfvi_field {
    double G;
    double softening2;
    size_t N_active;
    size_t n_images;
    const struct reb_vec6d* images;
    // Scratch for the pair scans (pfvi_timescales.c): particles 4 b .. 4 b + 3
    // in blocks[b], filled by pfvi_partner_search from its particles (and
    // read by pfvi_step_density, which calls it first with the same ones);
    // NULL, or room for fewer than N particles: each block gathered where
    // it is used.
    struct pfvi_lanes_block* blocks;
    size_t blocks_N;
};

// The orbit whose Kepler term is the density's largest: the body's position
// and velocity relative to its subsystem's barycentre, mu = G (m_i + M), and
// the term (pfvi_step_density).
struct pfvi_lead_orbit {
    double r[3], v[3];
    double mu;
    double term;
};

// A body's partner: the attracting body j != i (j < N_active, m_j > 0), or
// ghost image of one, of largest (m_i + m_j)/r^3 (r softened), the tightest
// pair i is in; the first of equal stiffnesses wins.
struct pfvi_partner {
    size_t j;           // SIZE_MAX: none (gravity off, G = 0, or no other attracting body)
    size_t image;       // the ghost box j's image lies in (0: the box itself)
    double stiffness;   // (m_i + m_j)/r^3, 0 without a partner
    double pull;        // m_j/r^2 (softened), and its d log/dt: filled by
    double dlog_pull;   // pfvi_step_density for the encounter terms' weights
};
// Every body's partner (pfvi_timescales.c).
PFVI_INTERNAL void pfvi_partner_search(const struct reb_particle* p, size_t N, const struct pfvi_field* f,
        struct pfvi_partner* out);
// The step density sigma of the symmetric control at the particles p (with
// the accelerations of `start`, or p's own if NULL) and its logarithmic
// time derivative: the smooth maximum of each body's Kepler term about the
// subsystem it orbits and each unbound pair's encounter term, for the
// method of order 2s - 2. Fills partners, and lead (if not NULL) with the
// orbit of the largest Kepler term (lead->term 0: none).
// Returns 0 (sigma = 0) if no body has a partner.
PFVI_INTERNAL int pfvi_step_density(const struct reb_particle* p, const struct pfvi_end_state* start, size_t N,
        const struct pfvi_field* f, int s, struct pfvi_partner* partners, double* sigma, double* dlog_sigma,
        struct pfvi_lead_orbit* lead);
// How well a step's s stages resolve one particle's force: |D|/A, D the
// leading coefficient of the polynomial through the values f[k] (the stage
// accelerations, or what a fitted step's quadrature carries of them;
// weights: the barycentric weights of the nodes on [0, 1]) and A the largest
// of the |a[k]| and scale2^(1/2); 0 if that is 0. The stages are measured
// once (pfvi_stage_spread: |D|^2 and the largest |a[k]|^2) and the ratio
// taken for each scale2 asked (pfvi_stage_resolution).
struct pfvi_stage_spread {
    double D2;          // |D|^2
    double A2;          // the largest |a[k]|^2
};
PFVI_INTERNAL struct pfvi_stage_spread pfvi_stage_spread(const double (*f)[3], const double (*a)[3],
        const double* weights, int s);
static inline double pfvi_stage_resolution(const struct pfvi_stage_spread* spread, double scale2){
    const double A2 = (scale2 > spread->A2) ? scale2 : spread->A2;
    return (A2 > 0.) ? sqrt(spread->D2/A2) : 0.;
}
// The square of the largest single pull G m_j/r^2 (softened; every
// attracting body j != i and ghost image) on particle i of p; 0 without gravity.
PFVI_INTERNAL double pfvi_largest_pull2(const struct reb_particle* p, size_t N, const struct pfvi_field* f, size_t i);
// Inspection (tests): each particle's partner in the simulation as it stands
// (out[i] = N: none); 0 if memory ran out.
PFVI_API int pfvi_partners(struct reb_simulation* r, size_t* out);
// Inspection (tests): whether the predictor takes the real particles as two
// bodies alone (pfvi_gravity_two_alone), without a rest to extrapolate.
PFVI_API int pfvi_two_alone(struct reb_simulation* r);
// Inspection (tests): out = (sigma, d log(sigma)/dt) of the symmetric control
// for s stages at the simulation as it stands (its accelerations are
// evaluated); 0 without pairs.
PFVI_API int pfvi_density_of(struct reb_simulation* r, int stages, double* out);
// The time the running integrate() was asked for, where r's integrator is
// pfvi (begin returns the one held before, NaN for none: end gives it back).
PFVI_API double pfvi_request_begin(struct reb_simulation* r, double t);
PFVI_API void pfvi_request_end(struct reb_simulation* r, double held);
// The options as the next step checks them: 1 valid, 0 refused (pfvi's
// error among REBOUND's messages), -1 not pfvi.
PFVI_API int pfvi_options_check(struct reb_simulation* r);

/* ------------------------------------------------ geometry (centre) */

// The centre of one particle's harmonic model over a step, c(t0 + t) =
// x + t v + t^2 acc/2, and the partner whose attraction the particle's
// frequency refers to (pfvi_centre.c).
struct pfvi_centre {
    double x[3];
    double v[3];
    double acc[3];      // its acceleration, constant over the step (0 but for "partner")
    double a[3];        // the partner's attraction on the particle (0 without a partner)
    double mu;          // G (m_i + m_partner), 0 without a partner
    size_t partner;     // SIZE_MAX: none (no other body attracts it)
};
// The centre's displacement and velocity t after the step's start (component k).
static inline double pfvi_centre_shift(const struct pfvi_centre* c, double t, int k){
    return t*c->v[k] + 0.5*t*t*c->acc[k];
}
static inline double pfvi_centre_velocity(const struct pfvi_centre* c, double t, int k){
    return c->v[k] + t*c->acc[k];
}
// The centres of N particles of masses p[i].m at the step's start, with
// the partners of pfvi_partner_search (NULL: none needed, every partner
// is none): with the centre "partner" the barycentre of the particle and
// its partner, with "barycentre" that of the attracting bodies, otherwise
// (and where a particle has no partner) the origin. An external field is
// given in the simulation frame.
PFVI_INTERNAL void pfvi_centres(const struct reb_particle* p, const struct pfvi_end_state* start, size_t N,
        size_t N_active, double G, int centre, const struct pfvi_partner* partners, struct pfvi_centre* c);
// The frequency a step fits a particle to (before limiting), from its
// position and velocity relative to its centre, d and w, and the
// acceleration the model refers to: with the centre "partner", the
// partner's attraction (the frequencies are the pair's), otherwise the
// particle's whole start acceleration a. 0 for fitting "none", omega for
// "fixed", |w x a|/|w|^2 for "curvature", sqrt(max(0, -a.d)/|d|^2) for
// "radial" (about a partner G (m + m_partner)/r^3: -omega^2 d is then the
// partner's whole attraction), the osculating mean motion about the partner
// for "mean-motion" (0 if unbound or without a partner).
PFVI_INTERNAL double pfvi_frequency(const struct pfvi_options* o, const struct reb_particle* p,
        const struct reb_particle* partner, const struct pfvi_centre* c, const double a[3]);
// sqrt(max(0, -a.d)/|d|^2): the frequency of the pull a exerts towards d = 0
// (d scaled before squaring); 0 if a points away, NaN if a is not a number.
PFVI_INTERNAL double pfvi_radial_frequency(const double d[3], const double a[3]);

// Statistics (REBOUND fields, saved in archives).
struct pfvi_statistics {
    uint64_t n_steps;
    uint64_t n_iterations;
    uint64_t iterations_max;
    double iterations_mean;
    double epsilon_effective;      // the epsilon the symmetric control used (epsilon within its range)
    uint64_t n_u_limited;
    uint64_t n_force_evaluations;
    double omega_min;
    double omega_max;
    uint64_t n_rejected;
    uint64_t n_attempts;
    uint64_t n_asymmetric;
    uint64_t n_unresolved;         // symmetric steps whose forces no shorter step resolved better
    double error_estimate;         // the step control's estimate for the last step taken
    uint64_t n_variational_evaluations; // force evaluations for the variational particles alone (their
                                   // tangent solve going on after the real one converged)
    uint64_t n_variational_unconverged; // steps whose tangent solve stopped short of round-off
    uint64_t n_solve_recovered;    // steps whose stage solve refreshed or dropped its Newton Jacobians
    uint64_t n_solve_halved;       // trial steps halved because their stage solve failed
    uint64_t n_outputs;            // output steps (pfvi_output.c): states shown at a requested time
    uint64_t n_contact_steps;      // steps retaken to end at a contact the step's path showed
    uint64_t n_contact_kept;       // steps kept past a predicted contact (PFVI_CONTACT_RETAKES)
};

// What a trial step found, committed only if the step is taken.
struct pfvi_trial_record {
    uint64_t n_limited;
    uint64_t rounds;
    uint64_t variational_evaluations; // force evaluations for the variational particles alone
    int variational_unconverged;   // their tangent solve stopped short of round-off
    double megno_dY;               // the step's increment of MEGNO's 2 int (t - t_0) delta.delta'/|delta|^2 dt
    double megno_Y_integral;       // int Y dt over the step (Y = that integral / (t - t_0)), for <Y>
    double change;                 // the stage solve's last relative change
    double omega_min;
    double omega_max;
    int solve_recovered;           // the stage solve refreshed or dropped its Jacobians
    int stage_failed;              // a force at a stage point was not finite (st->stage_fault)
};

struct pfvi_compensation {
    double x[3];
    double v[3];
};

// Everything besides the particles, N and t that REBOUND's force evaluation
// reads (gravity.c, boundary.c, the force hooks), kept with the last step's
// end acceleration: that acceleration is reused only if this is unchanged,
// bit for bit. Its fields, listed once: D(double), S(size_t), I(int;
// REBOUND keeps enums), P(pointer field), each with the REBOUND member it
// keeps (archives save a shown output's numbers by the same list).
#define PFVI_FORCE_MODEL_FIELDS(D, S, I, P) \
    D(G, G) D(softening, softening) D(opening_angle2, opening_angle2) D(root_size, root_size) \
    D(OMEGA, OMEGA) D(OMEGAZ, OMEGAZ) \
    S(N_root[0], N_root_x) S(N_root[1], N_root_y) S(N_root[2], N_root_z) S(N_active, N_active) \
    I(gravity, gravity) I(testparticle_type, testparticle_type) \
    I(force_is_velocity_dependent, force_is_velocity_dependent) I(boundary, boundary) \
    I(N_ghost[0], N_ghost_x) I(N_ghost[1], N_ghost_y) I(N_ghost[2], N_ghost_z) \
    P(additional_forces, additional_forces) P(gravity_custom, gravity_custom) P(extras, extras)

struct pfvi_force_model {
    double G;
    double softening;
    double opening_angle2;
    double root_size;
    double OMEGA;
    double OMEGAZ;
    size_t N_root[3];
    size_t N_active;
    int gravity;
    int testparticle_type;
    int force_is_velocity_dependent;
    int boundary;
    int N_ghost[3];
    void (*additional_forces)(struct reb_simulation* const r);
    void (*gravity_custom)(struct reb_simulation* const r);
    void* extras;
};

// Why a step was not taken. The layers below the glue record the cause and
// return a failure; pfvi_integrator.c (pfvi_report) alone writes the message.
enum pfvi_fault_kind {
    PFVI_FAULT_NONE = 0,
    PFVI_FAULT_MEMORY,          // n: particles
    PFVI_FAULT_N_CHANGED,       // n, n_after, kept, added, t; flag: 1 if the particles could be restored
    PFVI_FAULT_OVERFLOW,        // particle, t0; flag: 1 position, 0 velocity
    PFVI_FAULT_FORCE,           // particle, t
    PFVI_FAULT_POLE,            // particle, value: u, n: stages
    PFVI_FAULT_NOT_FINITE,      // particle, t0
    PFVI_FAULT_KICK,            // the implicit kick did not converge
    PFVI_FAULT_UNDERFLOW,       // h, n: stages
    PFVI_FAULT_NOT_CONVERGED,   // n: stages, value: change, rounds, t0
    PFVI_FAULT_REJECTED,        // t0, h, value: estimate
    PFVI_FAULT_UNSOLVED,        // t0, rounds: trials, h, value: F
    PFVI_FAULT_UNSTABLE,        // particle, h, n, value: omega, bound: its pull's frequency, growth: factor per step - 1
    PFVI_FAULT_CALLBACK_CHANGED,// t: a callback replaced additional_forces, gravity_custom or extras
    PFVI_FAULT_VARIATIONS_CHANGED, // t, n: N_var before, particle: N_var after (a callback added or removed variations)
    PFVI_FAULT_PARTICLE_EDITED, // t, particle (SIZE_MAX: t itself), flag: which field (pfvi_written_fields), n: 1 for a variational particle
    PFVI_FAULT_UNRESOLVED_FIXED,// particle, h, t0, value: the error per orbit the stages imply, bound: |h| sigma (0: not measured)
    PFVI_FAULT_VARIATIONAL,     // particle: the variational particle (index in particles_var), n: its real particle, flag: field (PFVI_WRITTEN_FIELDS), value, t0
    PFVI_FAULT_REBOUND_ERROR,   // t: REBOUND raised an error inside a force evaluation (its message says why)
};
struct pfvi_fault {
    enum pfvi_fault_kind kind;
    size_t particle;
    size_t n;
    size_t n_after;
    size_t kept;
    size_t added;
    double t0;
    double t;
    double h;
    double value;
    double bound;
    double growth;
    uint64_t rounds;
    int flag;
};

// A particle as pfvi set it before a force evaluation: a callback that edits
// any of these during a step (not between steps) has the step refused.
struct pfvi_written {
    double value[7];    // x, y, z, vx, vy, vz, m
};
#define PFVI_WRITTEN_FIELDS {"x", "y", "z", "vx", "vy", "vz", "m"}

// The steady track's state (struct pfvi_state's steady; PFVI_STEADY_WINDOW).
struct pfvi_steady {
    int hold;
    int n;
    double lo, hi;
    double t0, span;    // the window's start, and the slowest orbit's time scale seen in it
    double entry_t, entry_sign, entry_rho;   // (a hold begins without a jump: rho on both sides)
    double exit_t, exit_sign, exit_held, exit_after;
};

// A step of the symmetric control that was not time-symmetric (a retake,
// lambda falling back, the track's drift correction), logged so that a
// reversal replays it (issue 40, item 7): the step's ends, its direction,
// and the track as the step found it.
// The track's state a replayed step restores: fields of struct pfvi_state,
// one list for the log's declaration, its keeping and its restoring.
#define PFVI_TRACK_FIELDS(X) \
    X(double, rho) X(double, rho_sign) X(double, dt_proposed) X(double, track_done) X(int, track_at_end) \
    X(double, track_kappa) X(double, density_scale) X(double, dt_last_full) X(double, track_mismatch) \
    X(double, track_seen_lo) X(double, track_seen_hi) X(struct pfvi_steady, steady) \
    X(double, t_compensation) X(double, t_compensated)
#define PFVI_FIELD_DECLARE(type, name) type name;
struct pfvi_replay {
    double t_start, t_end, sign;
    int pin;    // a time-symmetric step logged as a pin (PFVI_REPLAY_PIN_EVERY)
    PFVI_TRACK_FIELDS(PFVI_FIELD_DECLARE)
};
#undef PFVI_FIELD_DECLARE
// The last this many are kept (a ring; older ones are not replayed; 232
// bytes each). With a pin every PFVI_REPLAY_PIN_EVERY steps they span 16384
// steps of pins alone (256 spanned 4096: the Encke-like comet in REBOUND's
// units, 5100 steps to t = 410 at epsilon 1e-7, lost its oldest pins and
// came back 1.5e-4 off on 11 of 30 round trips; none now, 4.1e-10).
#define PFVI_REPLAY_MAX 1024
// A track restarted by an edit takes the run's own proposal as its first
// interval where it is at least this fraction of the interval the edited
// state gives (pfvi_control.c).
// Below it the proposal is the rest of an interval cut at an output, and
// the steps would shrink from proposal to proposal (0.9 and 0.5 measured:
// a mass edited every step beside a retrograde comet, 149 and 91 steps at
// epsilon 1e-6, 105 unedited; no bound: 383 steps for 208 with 40 outputs).
#define PFVI_EDIT_TRACK_NEAR 0.5
// A reversal meets a logged step where its t is within this fraction of the
// step's length of the step's end; the replayed step lands on the logged
// start. The way back's grid drifts from the way out's: the rounding of the
// intervals, grown by the varying track between logged steps (the Encke-like
// comet at epsilon 1e-7, G = 1: 1e-13 of t at t = 329 to 8.4e-7, 2e-6 of
// the step, at t = 184.6; docs/step-control.md). A way back that misses an
// entry leaves it the newest, and no later one is replayed either: met
// within 1e-6 of the step, this comet's way back missed that one and came
// back 1.2e-6 off (3.1e-12 now). Grid points are steps apart, so a
// hundredth of the step still names one.
#define PFVI_REPLAY_T_SLACK 1e-2
// Every this many steps a whole interval no other cause logs is logged as a
// pin. A way back meeting a pin replays it only where its grid has drifted
// from the way out's by more than PFVI_REPLAY_PIN_DRIFT of the step; else it
// drops the pin and takes its own step, bit for bit as without pins. A
// replayed step lands on the logged start: that resynchronises a drifted
// grid, but on a grid that has not drifted it costs more than it mends (the
// way back's times differ from the way out's by the rounding of rho +- kappa
// G, up to 3e-12 on Kepler e = 0.5, which the symmetric steps undo by the
// end of the trip and a replay makes permanent: pins replayed every 8 steps
// took Kepler e = 0.91 from 7.4e-14 AU back to 2.9e-11; docs/step-control.md).
#define PFVI_REPLAY_PIN_EVERY 16
#define PFVI_REPLAY_PIN_DRIFT 1e-5

// Whether a snapshot was written inside an integrate() (struct pfvi_state's in_call).
// PFVI_CALL_STARTING_CUT: a simulation loaded from a call's start where
// REBOUND had cut sim.dt to finish, that a call since has not stepped
// (REBOUND's status, which said so, is gone).
enum { PFVI_CALL_UNKNOWN = 0, PFVI_CALL_INSIDE = 1, PFVI_CALL_BETWEEN = 2, PFVI_CALL_STARTING = 3,
       PFVI_CALL_STARTING_CUT = 4 };

// Integrator state: settings, statistics and the controller's state are
// REBOUND fields (saved in archives); the scratch grows only with N.
struct pfvi_state {
    // The options as set (REBOUND fields: Python, archives, and callbacks
    // during a step write them), and the copy the current step runs with,
    // taken when it starts: a change made during a step acts from the next.
    struct pfvi_options settings;
    struct pfvi_options options;
    struct pfvi_statistics statistics;
    // Controller state (saved): the last solution of the reversible step
    // equation; the symmetric step's density rho of the last step and the
    // direction it was taken in (rho = 0: start afresh).
    double dt_reversible;
    // The symmetric track: the density rho of the current interval between
    // two grid points (0: no track), the direction of the last step, how far
    // into the interval it ended (track_done, from the end it entered at;
    // track_at_end: at the far grid point), the kappa it was made with, the
    // scale lambda >= 1 of the density (raised where the stages showed a
    // time scale the density missed), the last r->dt proposed and the last
    // step no cap shortened (REBOUND restores sim.dt to it after an exact
    // finish: neither is taken as a cap).
    double rho;
    double rho_sign;
    double dt_proposed;
    double track_done;
    int track_at_end;
    double track_kappa;
    double density_scale;
    double dt_last_full;
    int track_edited;       // the track was dropped for an edit of the particles (until the next step is taken)
    int track_edited_before;    // so was the last step's (pfvi_control.c: where a fresh track starts)
    int track_restarted;        // the last step restarted the track (a density jump; pfvi_control.c)
    double track_mismatch;  // the average mismatch of rho and lambda sigma (PFVI_TRACK_MISMATCH_WEIGHT)
    double track_seen_lo;   // the time the average has seen: intervals a reversal retraces
    double track_seen_hi;   // within it are not averaged again (pfvi_control.c)
    // The steady track (PFVI_STEADY_WINDOW): held or not, the window so far
    // (its intervals and their end densities' range), and the last time the
    // hold began and ended (the direction, 0 for none, and rho on either
    // side), so that a reversal ends or resumes it where the way out did.
    struct pfvi_steady steady;
    // The asymmetric steps of the way so far, newest last (pfvi_control.c;
    // not saved in archives: a restarted run does not replay them).
    // (PFVI_REPLAY_MAX entries, allocated with the state and not cleared:
    // an entry is written before it is read. Inline and zeroed, its 238 kB
    // made the state's calloc 50 us of every sim.integrator = "pfvi".)
    struct pfvi_replay* replay;
    size_t replay_first, replay_n;
    // The next step is logged too: the last was the first half of a split
    // interval, or restarted the track (pfvi_control.c; not saved in archives).
    int replay_next;
    size_t replay_count[2];   // entries of the steps taken forward [0] and backward [1]
    // What the symmetric track's time lost to rounding: the state is at
    // r->t + t_compensation (0 if r->t is not t_compensated, the t it was
    // kept for), so that a step capped to finish on time, or an output
    // step, lands there. Folded into r->t every step (below half its last
    // place); PFVI_T_LO_MAX bounds what an archive or attribute may set.
    double t_compensation;
    double t_compensated;
    // The density at the end of the last step (and its partners), the next
    // step's start density if that step starts there (density_N > 0).
    size_t density_N;
    int density_stages;
    double density_sigma;
    double density_dlog;
    struct pfvi_trial_record trial;
    struct pfvi_fault fault;
    // A trial of this step met stage forces that were not finite (kind
    // FORCE or OVERFLOW; NONE otherwise): the stage solve took that as its
    // trial's failure, and the controls halve the step. Named (pfvi_give_up,
    // and where a step below t's rounding is all that is left) if no shorter
    // step helps.
    struct pfvi_fault stage_fault;
    // A fixed step's stages implied an error above PFVI_FIXED_WARN and
    // REBOUND was told (once per simulation; not saved).
    int fixed_warned;
    // A refused step's REBOUND hooks, held from the refusal to REBOUND's
    // synchronize at the end of the call (pfvi_integrator.c, pfvi_step):
    // the rest of REBOUND's step then runs none of them on the restored
    // state (not saved).
    int hooks_held;
    void (*held_pre)(struct reb_simulation* const r);
    void (*held_post)(struct reb_simulation* const r);
    void (*held_heartbeat)(struct reb_simulation* r);
    int held_collision;
    // kappa was below PFVI_KAPPA_WARN and REBOUND was told (once per simulation; not saved).
    int kappa_warned;
    // A step was kept unresolved and REBOUND was told (once per simulation; not saved).
    int unresolved_warned;
    // A stage force that was not finite halved a step (said once per
    // simulation; not saved).
    int stage_fault_warned;
    // Without pairs: consecutive steps retaken to a step that no longer
    // reached what made the first trial coarse (pfvi_control.c,
    // control_unpaired; saved).
    int unpaired_suspect;
    // Without pairs: the last step that count holds; a first trial kept at
    // once for the count is at most twice it (pfvi_control.c; saved).
    double dt_suspect;
    // Without pairs: 1 + the index of the body whose retakes that count
    // holds (0: none); the shortcut keeps only a trial worst at that body (saved).
    int suspect_body;
    // Without pairs: the longest step taken where no force varied (u = 0)
    // and none was retaken, or the run's first sim.dt if longer, which free
    // motion grows back to (saved).
    double dt_free;
    // Without pairs: whether the last step was retaken (the stages may then
    // be judged against the motion too: pfvi_control.c; saved).
    int unpaired_retaken;
    // Without pairs: consecutive steps retaken for their force's own
    // resolution and kept as resolved against the motion (pfvi_control.c; saved).
    int unpaired_crawl;

    // Scratch
    size_t N_allocated;
    struct reb_particle* start;    // bit-exact copy of the particles at the start of the step (rollback)
    struct pfvi_end_state* end;    // end of the last step, with its accelerations (force reuse)
    struct pfvi_two_point_fit* fit;// per-particle coefficients of the current two-point step
    struct reb_vec3d* v_rotated;   // velocities before the final kick (velocity-dependent forces)
    struct pfvi_written* written;  // what pfvi set before a force evaluation (a callback may not edit it)
    struct pfvi_written* written_var;   // the same for the variational particles (var_N of them)
    struct reb_vec3d* dx;          // position increment of the step, with the carried low-order part
    double (*end_low)[3];          // the s-point step's end increment's low part (solve_take_end): this trial's
    struct reb_vec3d* dv;          // velocity increment of the step, with the carried low-order part
    double (*dv_low)[3];           // what rounding the s-point step's dv lost (stages_advance): this trial's
    // Compensated summation: the low-order parts of x, y, z, vx, vy, vz that
    // the particles' doubles lost (Kahan). Saved in archives, so a continued
    // run stays bit-identical.
    struct pfvi_compensation* compensation;
    size_t N_compensation;
    // The frequency each particle is fitted to in this step, the curvature
    // frequency at its end (the controller's u bound), and the osculating
    // circles at its start.
    double* omega_fit;
    struct pfvi_centre* centre;    // each particle's centre in this step
    struct pfvi_partner* partners; // each particle's partner at the step's start (time scales, centres)
    // The partners at the start of the step being taken, for the resolution
    // check of the symmetric control, which reads both ends' (pfvi_control.c).
    struct pfvi_partner* partners_start;
    struct pfvi_partner* partners_scratch;   // a fresh track's placement (pfvi_control.c)
    struct reb_vec6d* images;      // the ghost boxes' shifts (pfvi_field_of)
    size_t images_allocated;
    double* omega_end;
    struct pfvi_osculating* osculating_start;
    // The s-stage solve: quadrature, per-particle fits, stage accelerations
    // a[i][k] of the step being tried, those of the last step taken (the
    // predictor's data), and the unknowns of the current and the next iterate.
    struct pfvi_lobatto rule;
    struct pfvi_stage_fit stage_classical;  // the rule's fit at u = 0, copied where omega is 0 ("none")
    struct pfvi_stage_fit* stage_fit;
    // stage_fit_classical[i] = s where stage_fit[i] is a copy of the
    // classical fit of s stages (stage_classical, the same for every rule
    // of s), 0 otherwise: a classical particle's fit, the same at every
    // step, is then not copied again (pfvi_stages.c). Cleared whenever the
    // buffers grow.
    unsigned char* stage_fit_classical;
    double (*stage_a)[PFVI_STAGES_MAX][3];
    double (*predictor_a)[PFVI_STAGES_MAX][3];
    // The positions at which stage_a (predictor_a) were evaluated or
    // predicted: "exact" solves the harmonic part of the force implicitly
    // and iterates on the residual a^k + omega^2 d^k only.
    double (*stage_x)[PFVI_STAGES_MAX][3];
    // pfvi_gravity_stages' positions and forces, component-major with the
    // stages as the innermost (vectorised) index.
    double (*gravity_x)[3][PFVI_STAGES_MAX];
    double (*gravity_a)[3][PFVI_STAGES_MAX];
    // The real gravity at the converged stage points while the tangent
    // solve goes on alone beside additional forces (stage_a keeps its own).
    double (*beside_a)[PFVI_STAGES_MAX][3];
    double (*predictor_x)[PFVI_STAGES_MAX][3];
    double (*unknowns)[PFVI_STAGES_MAX-1][3];
    double (*unknowns_next)[PFVI_STAGES_MAX-1][3];
    // The classical form's stage velocities V^k, for forces that depend on
    // velocities.
    double (*velocities)[PFVI_STAGES_MAX][3];
    // What each round of a step reuses, per particle (pfvi_stages.c).
    struct pfvi_stage_start* stage_start;
    // The stage solve (pfvi_solve.c): each particle's form (pointing into
    // solve_forms, or at the classical one every unfitted particle shares),
    // the stage points of the iterate the Jacobians are taken at, the
    // Newton units and the order they are corrected in.
    const struct pfvi_solve_form** solve_form;
    struct pfvi_solve_form* solve_forms;
    struct pfvi_solve_form solve_form_classical;
    // The s and h solve_form_classical was made for (0: none): it depends on
    // nothing else, and is made again only when either changes.
    int solve_form_classical_s;
    double solve_form_classical_h;
    double (*solve_x)[PFVI_STAGES_MAX][3];
    struct pfvi_newton* newton;
    size_t* newton_order;
    size_t* newton_index;
    unsigned char* newton_mark;
    double* solve_scale;           // each body's distance from its centre at the step's start
    double var_solve_change;       // the variational particles' last two changes in the solve's rounds
    double var_solve_previous;
    // The last step's stage accelerations seed the next solve if it starts
    // where that step ended (same s, N and t). Saved in archives with
    // predictor_a, so that a continued run is bit-identical.
    // The last trial of the step being taken, if its solve converged: a
    // retry from the same t0 starts from its stages when the step control
    // allows it (retry_allowed: the reversible controller, whose trials
    // solve the step equation; the accept/reject controller keeps a rejected
    // trial without trace). Not saved: it never outlives the step.
    int retry_allowed;
    int retry_valid;
    int retry_stages;
    double retry_t0;
    double retry_h;
    int predictor_stages;          // s of that step (0: none)
    size_t predictor_N;
    double predictor_h;
    double predictor_t;            // t at its end
    // The two-body predictor's rest weights (pfvi_solve.c: the last step's
    // Lagrange basis at this step's nodes, and their integral), which depend
    // only on s and the step ratio h/predictor_h: kept for the last ratio,
    // made again only when it or s changes (the steady track's steps are
    // equal). Not saved (0: none kept).
    // The symmetric control's constants of the options (pfvi_control.c:
    // kappa, the effective epsilon, the resolution check's threshold), which
    // depend only on s and epsilon: made again when either changes (pow's
    // results for the same arguments). Not saved (stages 0: none kept).
    struct pfvi_symmetric_constants {
        int stages;
        double epsilon;
        double kappa, epsilon_effective, u_target, above;
    } symmetric_constants;
    int predict_weights_s;
    double predict_weights_rho;
    struct pfvi_lanes_block* field_blocks;   // struct pfvi_field's blocks (pfvi_field_of), for field_blocks_N particles
    size_t field_blocks_N;
    struct pfvi_rest_weights {
        int extrapolated;
        double start[PFVI_STAGES_MAX];
        double last_t[PFVI_STAGES_MAX][PFVI_STAGES_MAX];   // last[k][m] as last_t[m][k]: the stages k as lanes
    } predict_weights;
    size_t cache_N;                // >0: `end` describes the particles, taken at cache_t under cache_model
    size_t end_N;                  // >0: `end` holds the particles as the last step left them (edits are
                                   // found against it; REBOUND's synchronize clears cache_N, not this)
    // end_N as archives keep it (end_N itself is not saved: a loaded
    // simulation reuses nothing of its last step). It lets the first step
    // after a load or copy see a particle edited after the snapshot's step
    // (a post-timestep hook, a heartbeat), as the run itself does
    // (pfvi_forget_edited): a copy of a run with mass loss in such a hook
    // ended 2e-6 off it.
    size_t end_saved_N;
    double cache_t;
    struct pfvi_force_model cache_model;
    // Particles added or removed by a callback during a step (a force
    // evaluation): origin[k] is the index at the step's start of the particle
    // now at k, or SIZE_MAX for one added since, so that a refused step can
    // restore every particle that is still there. Tracked only while a step
    // runs, set up at the first change (the hot path never touches it).
    int in_step;
    // The force model the step runs with (taken when it starts), and what a
    // callback set during the step (applied when it ends: a change acts from
    // the next step, as one made between steps).
    struct pfvi_force_model step_model;
    struct pfvi_force_model pending_model;
    int model_pending;
    // REBOUND freed this state during its step (a callback switched or
    // re-assigned the integrator): the step finishes, then the state goes.
    int free_pending;
    // A steps() or integrate() a callback called during the step was
    // refused; REBOUND's loop around it still set status (and may have
    // flipped dt's sign): both go back to the step's own after each force
    // evaluation, so that the run goes on as without the call.
    int reentry_refused;
    int status_at_start;
    double dt_at_start;
    // The time the running integrate() was asked for (pfvi_request_begin,
    // which rebound_pfvi's sim.integrate calls around REBOUND's): REBOUND
    // decides whether a step finishes by comparing t + sim.dt with it, and
    // what pfvi shows next may lie further, so a state that would pass it
    // shows it as a finishing step would. Not set: REBOUND's decision alone.
    int request_set;
    double request_t;
    int request_shown;      // this step call showed it (pfvi_integrator.c)
    // Where it was shown, what REBOUND's own finish would have left as sim.dt
    // (the dt_last_done the state past the time would have been shown with;
    // REBOUND, which did not finish, restores the dt the call began with):
    // set as the call ends. 0: REBOUND's restore stands.
    double request_dt_leaves;
    // A loaded or copied simulation whose call began on REBOUND's cut to
    // the requested time (its snapshot was written as REBOUND finished on
    // an output: sim.dt the cut, dt_last_done the run's step before it):
    // REBOUND restores the cut after the call, where the run it continues
    // had its step before the cut restored. request_dt_last_done: the
    // simulation's dt_last_done as the call began; request_loaded_cut: the
    // call's first step was that cut (pfvi_request_end puts the run's value back).
    double request_dt_last_done;
    int request_loaded_cut;
    // What pfvi_request_end puts back for request_loaded_cut: the
    // dt_last_done above, or, for a snapshot written between two finishing
    // steps of a call (request_began_last_step: the step control cut the
    // first short of the time, and REBOUND cut again without a new last full
    // step), the step before the first, which the run kept as
    // dt_rebound_leaves (before, a 'reversible' restart there went 3.5e-10
    // from the run).
    double request_dt_restore;
    int request_began_last_step;
    // sim.dt as the running integrate() found it (saved: a snapshot REBOUND
    // wrote at a call's start after cutting sim.dt to finish holds the cut,
    // and REBOUND restores this value after the call). request_entry_cut: a
    // simulation loaded from such a snapshot: that value, which
    // pfvi_request_end puts back as the run's REBOUND did; else 0.
    double dt_call_entry;
    double request_entry_cut;
    // What REBOUND restores sim.dt to after the running call (its last full
    // step: the dt_last_done before its first finishing step, else the value
    // the call began with), saved with request_dt_leaves, request_loaded_cut
    // and request_dt_restore: a snapshot REBOUND writes at a call's end
    // holds that restore, before pfvi_request_end replaces it.
    double dt_rebound_raw;
    // Whether an integrate() is running (PFVI_CALL_INSIDE; before its first
    // step, PFVI_CALL_STARTING) or not (PFVI_CALL_BETWEEN), saved: a
    // snapshot says whether it was written inside a call, as REBOUND's
    // archive writes them, or between calls, as a copy or sim.save_to_file
    // (PFVI_CALL_UNKNOWN: an archive written before 2026-11-29, or no
    // integrate() yet). snapshot_between_calls: this call's simulation was
    // loaded or copied from a snapshot written between calls or at a call's
    // start (REBOUND's first archive heartbeat, unless it cut sim.dt to
    // finish), whose sim.dt is the simulation's as the user left it: judged
    // as the run judged it (a value set after the copy caps; before, it was
    // taken for the snapshot's and a copy went 1e-11 from its original).
    int in_call;
    int snapshot_between_calls;
    // A shown output dropped because particles were added or removed
    // (pfvi_scratch) since: glue_entry takes it as an output edited, as any
    // other edit there (until read; never saved).
    int output_resized;
    // The sim.dt REBOUND leaves after an integrate() that ended on an output
    // (its last full step: the dt_last_done before the finishing step, or
    // the dt the call started with), so that a sim.dt the user sets after
    // the output is told from it and honoured (issue 40); 0: not known.
    double dt_rebound_leaves;
    // The sim.dt the last integrate() began with (REBOUND zeroes
    // dt_last_done as integrate() begins: a step that finds it zero, not
    // finishing, is a call's first), which REBOUND restores where no step of
    // the call was cut to finish (the run's step landed on the time itself);
    // kept only where it was pfvi's own value (its proposal, or a value
    // REBOUND restored from one), never a value the user set: REBOUND
    // restoring a user's sim.dt leaves the user's cap in place, and a user
    // cannot set a value of pfvi's by chance. 0: none.
    double dt_call_began;
    // dt_call_began is REBOUND's sim.dt of a new simulation (0.001), which
    // the first step does not take for a cap: taken for REBOUND's only by an
    // integrate() that finds the simulation still at the run's step end (a
    // user may set 0.001 before a steps()).
    int dt_call_default;
    // ... and it was found from a new simulation's first call whose first
    // step was its last (a requested time within REBOUND's 0.001, cut to
    // it): REBOUND restores its 0.001 after that call wherever the output
    // lies, so the next integrate() takes it for REBOUND's there too.
    int dt_call_first_cut;
    // sim.dt as REBOUND's last synchronize found it: REBOUND synchronizes
    // right before it cuts sim.dt to finish on a requested time, so on a
    // call's first step that finishes it is the dt the call began with (the
    // one REBOUND restores after the call).
    double dt_at_sync;
    // A new simulation's first step, cut by REBOUND to a time within the dt
    // its call began with: that dt (the step a single call would take
    // first; control_unpaired takes it, the output is shown from it); else 0.
    double dt_first_uncut;
    int call_is_integrate;   // this step's call found dt_last_done zero (integrate() begins so)
    // The last sim.dt a step found that was neither pfvi's nor REBOUND's: the
    // user's value. Never taken for REBOUND's restoring, even where REBOUND
    // restores it (the user's cap stands).
    double dt_user;
    // A step took dt_user in full: where REBOUND then restores it as the
    // call's last full step, pfvi_request_end leaves the run's proposal as
    // sim.dt instead, so that the next call tells a cap set again from one
    // REBOUND put back.
    int dt_user_spent;
    // Where the first call after a load or copy had its first step as its
    // last (REBOUND cut sim.dt to finish before pfvi saw the snapshot's),
    // that cut: a snapshot written as REBOUND finished on an output holds
    // the cut as sim.dt, and REBOUND restores it after the call.
    double dt_call_cut;
    int last_finishing;
    size_t step_N;
    // Variational particles (REBOUND's r->particles_var, first and second
    // order): each is stepped by the tangent map of its real particle's
    // step (pfvi_stages.c, pfvi_two_point.c): the same fit, centre and omega frozen at
    // the real step's (their tangent is zero), its forces REBOUND's
    // variational accelerations at its tangent stage points, evaluated in
    // the same calls as the real forces. They never change the real
    // particles' step, nor any check or step size.
    size_t var_N;                  // r->N_var of the step being taken (0: none)
    size_t var_allocated;
    size_t* var_real;              // the real particle whose fit each one's tangent step uses
    size_t* var_sets;              // the first of each set of N (a variation of every particle)
    size_t var_sets_N;
    struct reb_particle* var_start;// bit-exact copy at the step's start (rollback)
    struct pfvi_end_state* var_end;// as the last step left them, with their accelerations (force reuse)
    size_t var_end_N;              // >0: var_end holds them
    double (*var_stage_a)[PFVI_STAGES_MAX][3];
    double (*var_predictor_a)[PFVI_STAGES_MAX][3];
    double (*var_stage_x)[PFVI_STAGES_MAX][3];
    double (*var_predictor_x)[PFVI_STAGES_MAX][3];
    // pfvi_gravity_variational_stages' positions and forces, laid out as gravity_x's.
    double (*var_gravity_x)[3][PFVI_STAGES_MAX];
    double (*var_gravity_a)[3][PFVI_STAGES_MAX];
    double (*var_unknowns)[PFVI_STAGES_MAX-1][3];
    double (*var_unknowns_next)[PFVI_STAGES_MAX-1][3];
    struct pfvi_stage_start* var_stage_start;
    struct reb_vec3d* var_dv;      // the two-point step's velocity increment before the final kick
    size_t var_predictor_N;        // >0: var_predictor_* are the stages of the step predictor_* describe (saved)
    int var_retry_valid;           // var_stage_* hold the last trial's (a retry of the same step)
    // Outputs (pfvi_output.c). REBOUND finishing on a requested time (its
    // exact_finish_time) asks for a step cut short; the symmetric control
    // takes its whole interval instead and the simulation shows the state
    // at the requested time from an output step (a trial from the step's
    // end, never committed). The run's own state is kept here and taken up
    // again by the next step if nothing was edited. All but output_uncapped,
    // output_cut and output_failed_t are saved in archives.
    struct pfvi_output_particle* output_real;   // the run's state at output_t_real
    struct pfvi_output_particle* output_shown;  // what the simulation was given at output_t
    size_t output_N;               // >0: an output is shown (the number of particles)
    struct pfvi_output_particle* output_var_real;   // the variational particles likewise
    struct pfvi_output_particle* output_var_shown;
    size_t output_var_N;
    // What archives save of the two pairs of buffers above: their allocated
    // length, never 0 once allocated (output_N and output_var_N are saved as
    // fields of their own). REBOUND's archive stores each snapshot after the
    // first as a difference from the first, and a buffer present there but
    // empty later was written as a field header without its data: the file
    // then crashed REBOUND's reader (a hostile trial: an archive begun
    // after an output).
    size_t output_saved_N;
    size_t output_var_saved_N;
    // The same for the stages of the last step (predictor_*, var_predictor_*)
    // and its end (end): their allocated length is what archives write, and
    // predictor_N, var_predictor_N and end_saved_N are saved as fields of
    // their own. Those fell to 0 after a refused step, an edit, a change to
    // stages = 2 with MEGNO or a load with fewer particles, and REBOUND then
    // could not open the archive (a hostile trial, six ways). counts_saved:
    // 1 in any snapshot written after a step, 0 in one an older build wrote,
    // whose buffers were saved at those counts (pfvi_scratch takes them).
    size_t predictor_length;
    size_t var_predictor_length;
    size_t end_length;
    int counts_saved;
    double output_megno[2][2];     // REBOUND's megno_Ys and megno_Yss: the run's [0] and shown [1]
    double output_t;
    double output_t_real;
    // The symmetric control's last step: the time its end force was evaluated
    // at and the time its state was labelled with (t folded with its
    // rounding, or the time REBOUND asked for): a forces check at the run's
    // state evaluates at the former (not saved: after a load, t itself).
    double end_force_t;
    double end_force_label;
    int output_stages;             // the options the shown output was made with
    double output_epsilon;
    struct pfvi_force_model output_model;   // and the force model (its numbers saved)
    int output_model_saved;        // 1: output_model was kept (archives before 2026-11-29 have none)
    struct pfvi_output_check* output_check;   // (output_check_N of them: 0 from an archive without them)
    size_t output_check_N;
    double output_exit_min_distance;   // REBOUND's contact settings the output was shown with
    int output_collision;
    double output_last_t0;         // the last real step went from output_last_t0 to output_last_t1
    double output_last_t1;
    int output_uncapped;           // set by the glue: the symmetric control takes the whole interval
    int output_cut;                // set by the glue: hooks need REBOUND's own outputs and sim.dt is not
                                   // the run's proposal (REBOUND's cut, default or restored value): it caps
    int output_taken_up;           // set by the glue: the step starts from the run's state, its force kept
    int output_contact_pending;    // the run's state kept ends a step retaken at a contact that an output
                                   // was shown before: REBOUND has not seen it yet (saved)
    double output_failed_t;        // an output step from the state at this t did not converge (NaN: none)
    // MEGNO's stage velocities: w_k = w_0 + h sum_j collocation[k][j] a_j,
    // collocation[k][j] the integral of l_j from 0 to c^k (Lobatto IIIA), for s = collocation_s.
    double collocation[PFVI_STAGES_MAX][PFVI_STAGES_MAX];
    int collocation_s;
    size_t* origin;
    size_t origin_N;
    size_t origin_allocated;
    // Contacts inside a step (pfvi_contact.c): consecutive steps retaken at
    // a contact (saved), the inverse of the path polynomial's conditions for
    // contact_s stages (0: not computed), and scratch grown only with N.
    int contact_chain;
    int contact_s;
    double contact_inverse[2*PFVI_STAGES_MAX+2][2*PFVI_STAGES_MAX+2];
    size_t contact_allocated;
    struct pfvi_contact_body* contact_bodies;
    size_t* contact_order;
    struct pfvi_compensation* contact_compensation;
};

enum { PFVI_STEP_IDLE = 0, PFVI_STEP_RUNNING = 1, PFVI_STEP_TRACKING = 2, PFVI_STEP_UNTRACKED = 3 };

// pfvi_state.c
PFVI_INTERNAL void pfvi_state_free(struct pfvi_state* st);
// Scratch for N particles (grows only when N does); 0 (fault recorded) if memory ran out.
PFVI_INTERNAL int pfvi_scratch(struct pfvi_state* st, size_t N);
// The contact search's scratch (pfvi_contact.c's boxes, order and compensation), grown with N.
PFVI_INTERNAL int pfvi_contact_scratch(struct pfvi_state* st, size_t N);
PFVI_INTERNAL int pfvi_particle_finite(const struct reb_particle* p);
// The first particle with a non-finite position, velocity or mass; SIZE_MAX if none.
PFVI_INTERNAL size_t pfvi_first_not_finite(const struct reb_particle* ps, size_t N);
// Whether the particles, N, t and the force model are, bit for bit, those the last step ended with.
PFVI_INTERNAL int pfvi_end_is_start(const struct reb_simulation* r, const struct pfvi_state* st);
// Whether the particles, N, t and the force model are those the last step
// ended with, whatever happened between (a synchronize, a new integrate()).
PFVI_INTERNAL int pfvi_state_is_end(const struct reb_simulation* r, const struct pfvi_state* st);
// Keeps the end of the step just taken as the next step's start (force reuse).
PFVI_INTERNAL void pfvi_keep_end(const struct reb_simulation* r, struct pfvi_state* st, size_t N);
// Marks st->end (set by the caller) as the particles at r->t under the current force model.
PFVI_INTERNAL void pfvi_keep_end_model(const struct reb_simulation* r, struct pfvi_state* st, size_t N);
// Drops what particles edited since the last step carried (compensation, predictor).
PFVI_INTERNAL void pfvi_forget_edited(const struct reb_simulation* r, struct pfvi_state* st);
// Empties the replay log of the symmetric control (pfvi_control.c), its counts with it.
PFVI_INTERNAL void pfvi_replay_clear(struct pfvi_state* st);
// The field the time scales see (struct pfvi_field): REBOUND's G (0 with
// gravity off), softening, N_active and its ghost boxes at r->t (in st's
// scratch); 0 (fault recorded) if memory ran out.
PFVI_INTERNAL int pfvi_field_of(const struct reb_simulation* r, struct pfvi_state* st, struct pfvi_field* f);
// The number of ghost boxes REBOUND sums over, and their shifts at r->t
// into images (room for that many), in the order of pfvi_field.
PFVI_INTERNAL size_t pfvi_ghost_box_count(const struct reb_simulation* r);
PFVI_INTERNAL void pfvi_ghost_boxes(const struct reb_simulation* r, struct reb_vec6d* images);
// Discards stored state that no step of pfvi's could have left (from an
// archive or set by hand: NaN, infinite, a zero step, a scale below 1, a
// carried part above the doubles' precision): the predictor, the symmetric
// track and the carried parts start afresh, as after an edit.
PFVI_INTERNAL void pfvi_discard_implausible(const struct reb_simulation* r, struct pfvi_state* st);
// What r->t lacks of the state's time: st->t_compensation if it was kept for
// this t and is plausible (pfvi_t_lo_plausible), else 0.
PFVI_INTERNAL double pfvi_t_lo(const struct reb_simulation* r, const struct pfvi_state* st);
PFVI_INTERNAL int pfvi_t_lo_plausible(double t_lo, double t);
// The force model as the step starts (kept in step_model), and, after the
// step, what a callback set during it, applied.
PFVI_INTERNAL void pfvi_step_model_keep(const struct reb_simulation* r, struct pfvi_state* st);
PFVI_INTERNAL void pfvi_step_model_apply_pending(struct reb_simulation* r, struct pfvi_state* st);
// Puts every particle (all fields) and t back to the start of the step.
PFVI_INTERNAL void pfvi_roll_back(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0);
// A control's refusal when no shorter step is left: fault, or the stage
// forces of this step's trials that were not finite (st->stage_fault), the cause.
PFVI_INTERNAL void pfvi_give_up(struct pfvi_state* st, struct pfvi_fault fault);
// Evaluates forces through REBOUND; 0 (rolled back, fault recorded) if they
// are not finite or a callback changed N.
PFVI_INTERNAL int pfvi_update_acceleration(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0);
// The same with REBOUND's basic gravity already in the particles'
// accelerations (pfvi_gravity_stages'): only the additional forces are called.
PFVI_INTERNAL int pfvi_update_additional_forces(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0);
// Whether the forces run user code (additional_forces, REBOUNDx, custom
// gravity): code that may edit particles during an evaluation, and whose
// forces no field of REBOUND's describes.
PFVI_INTERNAL int pfvi_forces_run_user_code(const struct reb_simulation* r);
// REBOUND's error messages held, and its newest message (pfvi_state.c):
// whether an error was said since a mark.
struct pfvi_error_mark {
    int n;
    const char* newest;
};
PFVI_INTERNAL struct pfvi_error_mark pfvi_rebound_errors(const struct reb_simulation* r);
PFVI_INTERNAL int pfvi_rebound_error_since(const struct reb_simulation* r, struct pfvi_error_mark before);
// An error (sim.integrate() raises it in Python) or a warning through
// REBOUND, printf-style. REBOUND keeps at most REB_STRING_SIZE_MAX - 2
// characters of a message and cuts the rest anywhere (a hostile trial: "...
// smooth it, or "): a message that long ends at its last whole clause that
// fits. (The messages are written to fit with the widest numbers; this is
// the guard.)
PFVI_INTERNAL void pfvi_error(struct reb_simulation* r, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
PFVI_INTERNAL void pfvi_warning(struct reb_simulation* r, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
// pfvi_gravity.c: whether REBOUND's routine would compute only its basic
// gravity (no additional forces, variations, ignored terms or ghost boxes
// that move with t: a shearing sheet's),
// which pfvi_gravity_stages then computes at stages k0 .. k1 of positions x
// into a in one pass, bit for bit as REBOUND would stage by stage; 0 if a
// force is not finite (a is written all the same).
PFVI_INTERNAL int pfvi_gravity_own(const struct reb_simulation* r, const struct pfvi_state* st, size_t N);
// Whether the real particles are two bodies whose only force is their
// mutual pull (REBOUND's basic gravity with G > 0 between two active bodies,
// no ghost boxes, nothing added; variational particles may be there): each body's
// acceleration is then the pair's Kepler pull about their barycentre,
// which moves uniformly, and what the predictor would call the rest of it
// is round-off.
PFVI_INTERNAL int pfvi_gravity_two_alone(const struct reb_simulation* r, size_t N);
// Whether REBOUND's routine would compute its basic gravity and then call
// additional forces (a force callback, REBOUNDx's): the gravity can be
// pfvi_gravity_stages', the forces called at each stage beside it.
PFVI_INTERNAL int pfvi_gravity_own_beside_forces(const struct reb_simulation* r, const struct pfvi_state* st, size_t N);
PFVI_INTERNAL int pfvi_gravity_stages(const struct reb_simulation* r, struct pfvi_state* st, size_t N,
        const double (*x)[PFVI_STAGES_MAX][3], double (*a)[PFVI_STAGES_MAX][3], int k0, int k1);
// Whether REBOUND's routine would compute the variational particles' forces
// with its basic variational gravity alone (first order, whole sets, no
// ghost boxes, nothing called after): pfvi_gravity_variational_stages then
// computes them at stages k0 .. k1 of the real positions x and the
// variational dx into da, bit for bit as REBOUND would stage by stage.
PFVI_INTERNAL int pfvi_gravity_own_variational(const struct reb_simulation* r, const struct pfvi_state* st, size_t N);
// The same with additional forces called after the gravity: the real and
// variational gravity can be the pass's, the forces called at each stage beside it.
PFVI_INTERNAL int pfvi_gravity_own_variational_beside_forces(const struct reb_simulation* r,
        const struct pfvi_state* st, size_t N);
PFVI_INTERNAL void pfvi_gravity_variational_stages(const struct reb_simulation* r, struct pfvi_state* st, size_t N,
        const double (*x)[PFVI_STAGES_MAX][3], const double (*dx)[PFVI_STAGES_MAX][3],
        double (*da)[PFVI_STAGES_MAX][3], int k0, int k1);
PFVI_INTERNAL void pfvi_track_added(struct pfvi_state* st);
PFVI_INTERNAL void pfvi_track_removed(struct pfvi_state* st, size_t index);
// The stopping rule of the two-point step's implicit kick (velocity-dependent forces).
enum pfvi_iteration { PFVI_ITERATE = 0, PFVI_CONVERGED = 1, PFVI_FAILED = -1 };
PFVI_INTERNAL enum pfvi_iteration pfvi_iteration_verdict(double change, double previous, int last_round);
// Scratch for the n variational particles (grows only with n); 0 (fault recorded) if memory ran out.
PFVI_INTERNAL int pfvi_var_scratch(struct pfvi_state* st, size_t n);
// Each variational particle's real particle (var_real), from REBOUND's
// configurations; 0 if they do not describe r->N_var particles of r->N.
PFVI_INTERNAL int pfvi_var_map(const struct reb_simulation* r, struct pfvi_state* st);
// Whether the variational particles are, bit for bit, those the last step left.
PFVI_INTERNAL int pfvi_var_is_end(const struct reb_simulation* r, const struct pfvi_state* st);
PFVI_INTERNAL void pfvi_var_keep_end(const struct reb_simulation* r, struct pfvi_state* st);

// MEGNO's increment over a step from t (relative to megno_initial_t) to
// t + h: 2 int (t' - t_0) d ln|delta| = 2 [(t + h) L1 - t L0 - int ln|delta| dt'],
// by parts, L0 and L1 ln|delta| at the step's ends and `integral` the
// scheme's quadrature of ln|delta| over its stages (docs/megno.md).
static inline double megno_increment(double t, double h, double L0, double L1, double integral){
    return 2.*(((t + h)*L1 - t*L0) - integral);
}
// Y at a time t after megno_initial_t from the running sum Ys there (0 at t = 0, its limit).
static inline double megno_Y(double Ys, double t){
    return (t != 0.) ? Ys/t : 0.;
}

/* ------------------------------------------------------------ stage solve */

// Outcome of one trial step. A trial leaves the end state in the particles
// and commits nothing; on anything but PFVI_TRIAL_OK the particles and t are
// already rolled back.
enum pfvi_trial {
    PFVI_TRIAL_OK = 1,
    PFVI_TRIAL_ERROR = 0,            // refused, fault recorded
    PFVI_TRIAL_NOT_CONVERGED = -1,   // the stage solve did not converge (shorter steps may)
};


// What a scheme hands the stage solve (pfvi_stages.c's two forms): the
// forces at the stage points of the iterate st->unknowns (stages k_first ..
// k_last, and stage 0 too where forces depend on velocities; 0 if refused,
// rolled back), one round unknowns_next = G(unknowns) for the real and
// variational particles, and the stage points of unknowns into solve_x.
struct pfvi_solve_ops {
    int (*forces)(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h,
            int k_first, int k_last);
    void (*round)(struct pfvi_state* st, size_t N, double h);
    void (*positions)(struct pfvi_state* st, size_t N, double h);
    // The iterate whose stage points are solve_x, for the particles whose
    // form can take it (the others keep theirs).
    void (*start_at)(struct pfvi_state* st, size_t N);
    // The variational particles' change in the round just made (their own verdict's).
    void (*variational_change)(struct pfvi_state* st);
};
// Where a scheme's first iterate came from: the last trial of this same step
// (a retry: kept), or the last step's stages (extrapolated), or neither.
enum { PFVI_PREDICTED_NONE = 0, PFVI_PREDICTED_RETRY = 1, PFVI_PREDICTED_EXTRAPOLATED = 2 };
enum pfvi_solve_next { PFVI_SOLVE_ITERATE = 0, PFVI_SOLVE_FINAL = 1, PFVI_SOLVE_CONVERGED = 2,
    PFVI_SOLVE_DIVERGING = 3, PFVI_SOLVE_STALLED = 4, PFVI_SOLVE_FAILED = -1 };
// The largest change of one particle's unknowns y -> yn, relative to the
// larger of |q0|, its step's increment y[increment] and scale; NaN kept.
PFVI_INTERNAL double pfvi_solve_change(const double (*y)[3], const double (*yn)[3], const double* q0,
        int increment, int s, double scale);
// The stop rule (PFVI_SOLVE_RESOLUTION): after a correction of size change
// following one of size previous (stalled: the last verdict was STALLED).
PFVI_INTERNAL enum pfvi_solve_next pfvi_solve_verdict(double change, double previous, int stalled, int last_round);
// The next iterate becomes the current one (real and variational particles).
PFVI_INTERNAL void pfvi_solve_swap(struct pfvi_state* st);
// The Newton units at the stage points solve_x (partners: st->partners);
// 0 if some body's matrix was singular (that body takes the plain round).
PFVI_INTERNAL int pfvi_newton_prepare(struct pfvi_state* st, size_t N, const struct pfvi_field* field);
// yn <- y + M^-1 (yn - y) for every unit.
PFVI_INTERNAL void pfvi_newton_correct(struct pfvi_state* st, size_t N, const double (*y)[PFVI_STAGES_MAX-1][3],
        double (*yn)[PFVI_STAGES_MAX-1][3]);
// The same for the variational particles (var_unknowns -> var_unknowns_next):
// their tangent equations are linear, with the real stages' Jacobian, so the
// real units' factors correct them (a set of N variations as the real
// particles are; a test particle's variation alone, about a fixed centre).
PFVI_INTERNAL void pfvi_newton_correct_variational(struct pfvi_state* st, size_t N);
// The rounds from the first iterate in st->unknowns to convergence: OK
// (unknowns converged, stage_a and stage_x at its stage points, every
// stage), NOT_CONVERGED, or ERROR (rolled back, fault recorded).
PFVI_INTERNAL enum pfvi_trial pfvi_solve_stages(struct reb_simulation* r, struct pfvi_state* st, size_t N,
        double t0, double h, const struct pfvi_solve_ops* ops, int predicted);
// The two-body predictor: each body's stage points (solve_x) along its
// two-body orbit about its partner, mutual pairs about their barycentre,
// the rest of the acceleration extrapolated from the last step's stages
// (extrapolate) or held at its start value; with rest = 0 no rest at all
// (two bodies alone, pfvi_gravity_two_alone: the rest is round-off).
PFVI_INTERNAL void pfvi_solve_predict(struct pfvi_state* st, size_t N, const struct pfvi_field* field, double h,
        int extrapolate, int rest);

/* ------------------------------------------------------- schemes and step */

// A scheme is a table on the one stepping skeleton of pfvi_step.c: its fit of
// one particle, the fitted frequency, the advance of all particles (forces
// through REBOUND) and what it keeps when a step is taken.
struct pfvi_scheme {
    // Before the fits: 0 (fault recorded) if the scheme cannot take a step of h.
    int (*prepare)(struct pfvi_state* st, double h);
    enum pfvi_fit_status (*fit)(struct pfvi_state* st, size_t i, double omega, double h);
    void (*copy_fit)(struct pfvi_state* st, size_t i, size_t from);
    double (*fitted_omega)(const struct pfvi_state* st, size_t i);
    // Moves the particles to the step's end; on failure rolled back.
    enum pfvi_trial (*advance)(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h);
    void (*commit)(struct reb_simulation* r, struct pfvi_state* st, size_t N, double h);
    // After a trial: the accelerations of particle i at the step's s nodes.
    void (*stage_accelerations)(const struct reb_simulation* r, const struct pfvi_state* st, size_t i,
            double (*a)[3]);
    // ... and its positions there (at which those were evaluated).
    void (*stage_positions)(const struct reb_simulation* r, const struct pfvi_state* st, size_t i,
            double (*x)[3]);
    // After the fits: half the trace of the step's linear map of (d, w) for
    // particle i as fitted, moving in 1-D under the pull a = -W2 d towards
    // its centre. Above 1 (the determinant is 1) a deviation grows
    // geometrically, by t + sqrt(t^2 - 1) per step: the step is unstable.
    double (*half_trace)(const struct pfvi_state* st, size_t i, double h, double W2);
};
PFVI_INTERNAL extern const struct pfvi_scheme pfvi_two_point_scheme;  // pfvi_two_point.c
PFVI_INTERNAL extern const struct pfvi_scheme pfvi_stages_scheme;     // pfvi_stages.c

// pfvi_step.c: one trial step of the scheme for the current stages, its commit.
PFVI_INTERNAL enum pfvi_trial pfvi_trial_step(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h);
PFVI_INTERNAL void pfvi_commit_step(struct reb_simulation* r, struct pfvi_state* st, size_t N, double h);
// How well the trial of h just made resolves the forces: the largest
// pfvi_stage_resolution over the particles, and which. A particle above
// pull_above against its net acceleration is measured against the largest
// pull on it at the step's start or end too (if field is not NULL); with
// residual, a fitted particle's values are its stage accelerations less the
// harmonic pull -omega^2 d its fitted path carries (the residual). With
// motion > 0, against motion |v|/|h| too (|v| the larger speed at the step's
// ends): an acceleration whose whole kick over the step is below motion
// times the body's speed cannot move it by that fraction of its path,
// resolved or not.
struct pfvi_resolution {
    double ratio;
    size_t particle;    // SIZE_MAX: none
    double own;         // the largest ratio without the motion floor
    int varies;         // with a motion floor: whether any body's stage accelerations differ
};
PFVI_INTERNAL struct pfvi_resolution pfvi_trial_resolution(const struct reb_simulation* r, const struct pfvi_state* st,
        size_t N, double h, const struct pfvi_field* field, double pull_above, int residual, double motion);
// The error per orbit a step of resolution u implies at s stages (where a
// Kepler orbit is resolved worst: PFVI_SYMMETRIC_CONSTANTS at u =
// PFVI_RESOLUTION_CONSTANTS kappa), and its inverse.
PFVI_INTERNAL double pfvi_resolution_error(int s, double u);
PFVI_INTERNAL double pfvi_resolution_of_error(int s, double error);
// The check of a fixed step (epsilon = 0) just tried: its resolution u, the
// error per orbit that implies, and the particle where it is worst. 0 (rolled
// back, fault recorded) if memory ran out.
struct pfvi_fixed_check {
    double u;
    double error;
    size_t particle;
    double kappa;           // |h| sigma, or |h| n at a pericentre inside the step if larger; 0 if not computed (PFVI_FIXED_GATE)
    size_t pericentre;      // the body whose pericentre gave kappa, SIZE_MAX if none
    int refuse;
    int saturated;          // u above PFVI_FIXED_GATE of its bound: the estimate is a lower bound
};
// 0 if the step is refused (rolled back, fault recorded: it is longer than
// PFVI_FIXED_KAPPA_MAX/sigma) or memory ran out; fills out either way.
// Whether every variational particle is finite at the step's start (x, v
// and m); if not, a fault naming the first and its field (nothing changed).
PFVI_INTERNAL int pfvi_var_start_finite(const struct reb_simulation* r, struct pfvi_state* st, double t0);
PFVI_INTERNAL int pfvi_fixed_step_check(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h,
        struct pfvi_fixed_check* out);


/* ---------------------------------------------------------------- outputs */

// pfvi_output.c: outputs that leave the run's steps as they are.
// Whether no hook is set that an output step cannot keep consistent (ODEs,
// pre- or post-timestep modifications).
PFVI_INTERNAL int pfvi_output_hooks_kept(const struct reb_simulation* r);
// Whether this step may take its whole interval and show an output instead
// of a step cut short (symmetric control, epsilon > 0, fitting 'none', the
// hooks kept).
PFVI_INTERNAL int pfvi_output_eligible(const struct reb_simulation* r, const struct pfvi_state* st);
// Whether the simulation still shows the kept output, unedited: N, N_var, t,
// every position, velocity and mass (variational ones too), stages, epsilon
// and the force model as they were.
PFVI_INTERNAL int pfvi_output_is_shown(const struct reb_simulation* r, const struct pfvi_state* st);
// Puts the run's own state (output_real, output_t_real) into the simulation.
PFVI_INTERNAL void pfvi_output_take_up(struct reb_simulation* r, struct pfvi_state* st);
// REBOUND's periodic wrap of the state in the simulation (reb_boundary_check,
// which REBOUND applies after every step), where it would have met the run's
// own end kept behind an output; 1 if it moved a particle.
PFVI_INTERNAL int pfvi_output_boundary(struct reb_simulation* r);
// REBOUND's open boundary (reb_boundary_check: the bodies that left the box
// removed) applied to the run's own end before an output is drawn from it;
// 1 if it removed any.
PFVI_INTERNAL int pfvi_output_removed(struct reb_simulation* r);
// Where the simulation is the run's last step's end moved by REBOUND's
// periodic wrap, puts the end's positions back and returns 1; else 0, the
// simulation as it was.
PFVI_INTERNAL int pfvi_output_unwrap(struct reb_simulation* r, struct pfvi_state* st);
// Whether the forces still are those the run's step past the shown output
// was made with: where they include what pfvi cannot see into (a callback's
// own variables, REBOUNDx's forces and parameters, custom gravity), one
// evaluation at the run's state, compared bit for bit with the force its
// step ended with. 1: they are (or nothing hidden), 0: not, -1: the
// evaluation was refused (st->fault says why). The shown output is back in
// the simulation either way.
PFVI_INTERNAL int pfvi_output_forces_hold(struct reb_simulation* r, struct pfvi_state* st);
// Puts the shown output back (a step refused after pfvi_output_take_up).
PFVI_INTERNAL void pfvi_output_show_again(struct reb_simulation* r, struct pfvi_state* st);
// From the run's state at r->t (the end of the last step, its forces in
// st->end), the state at t_out by one trial step of t_out - r->t, shown
// with r->t = t_out; the run's state kept. Returns the trial's verdict; on
// anything but PFVI_TRIAL_OK the run's state is back in the simulation and
// the kept output (output_N, output_shown) as it was.
// With `as_is`, the state is shown at t_out unchanged (PFVI_OUTPUT_NEAR).
PFVI_INTERNAL enum pfvi_trial pfvi_output_present(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t_out,
        int as_is);
// Whether the force model is the one the last step ended with (1 if no step is kept).
PFVI_INTERNAL int pfvi_force_model_kept(const struct reb_simulation* r, const struct pfvi_state* st);
// Keeps the force model a shown output was drawn under (saved in archives).
PFVI_INTERNAL void pfvi_output_keep_model(const struct reb_simulation* r, struct pfvi_state* st);

/* ---------------------------------------------------------- step control */

// pfvi_control.c: takes one step with the controller of options.step_control;
// returns the h taken, or 0 (rolled back, fault recorded) if none could be.
PFVI_INTERNAL double pfvi_controlled_step(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0);

/* -------------------------------------------------------------- contacts */

// pfvi_contact.c: whether a step must be searched for contacts (collisions
// on with a radius set, or exit_min_distance set; O(N) only with collisions on).
PFVI_INTERNAL int pfvi_contact_enabled(const struct reb_simulation* r);
// Whether REBOUND's collision search draws straight segments over the step ('line', 'linetree').
PFVI_INTERNAL int pfvi_contact_line(const struct reb_simulation* r);
// Takes one step with `take` (the fixed or controlled step) and, if the
// step's path shows a contact before its end, retakes it to end there
// (rolled back, the controller as before the step, the step capped by
// sim.dt). Returns the h taken, 0 if none (fault recorded).
struct pfvi_contact_body {
    double lo[PFVI_STAGES_MAX-1][3];  // the box of its path between nodes k and k + 1, with
    double hi[PFVI_STAGES_MAX-1][3];  // its sag, its radius and half exit_min_distance
    double sag;      // how far its path may leave the chords between its nodes
};
PFVI_INTERNAL double pfvi_contact_step(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0,
        double (*take)(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0));

/* ------------------------------------------------------------------ glue */

extern const struct reb_integrator pfvi_integrator;
PFVI_API int pfvi_register(void);
PFVI_API const char* pfvi_rebound_version_compiled(void);
PFVI_API size_t pfvi_sizeof_simulation(void);
PFVI_API size_t pfvi_sizeof_particle(void);
// The allowed numbers of stages, PFVI_STAGES_MIN and PFVI_STAGES_MAX, for Python.
PFVI_API void pfvi_stages_range(int* min, int* max);
// The names of an option's values, for Python: name of value index i of
// option `field` ("fitting", "frequency", "step_control"), NULL past the last.
PFVI_API const char* pfvi_option_value_name(const char* field, int i);

#endif // PFVI_H
