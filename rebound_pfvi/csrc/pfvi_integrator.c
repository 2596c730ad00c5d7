/**
 * pfvi_integrator.c: the REBOUND glue of the "pfvi" integrator (the top layer,
 * pfvi.h): the integrator table, its fields and their documentation (which
 * becomes Python's help(sim.integrator)), the options' validation, the step
 * entry (start force, frequencies, fixed step or step control) and the one
 * place where a refused step's cause becomes REBOUND's error message.
 */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "pfvi.h"
#include "rebound_internal.h"
#include "tools.h"

static void pfvi_step(struct reb_simulation* r, void* state);
static void pfvi_synchronize(struct reb_simulation* r, void* state);
static void pfvi_did_add_particle(struct reb_simulation* r);
static void pfvi_will_remove_particle(struct reb_simulation* r, size_t index);
static void* pfvi_create(void);
static void pfvi_free(void* state);
static const struct reb_binarydata_field_descriptor pfvi_field_descriptor_list[];

const struct reb_integrator pfvi_integrator = {
    .documentation =
    /* The summary a user reads first (at most 15 lines of help(sim.integrator));
     * its figures are docs/epsilon-match.md's (benchmarks/epsilon_match.py),
     * and tests/test_stated_figures.py fails while they differ. */
    "In short: adaptive, time-symmetric steps of order 14 (stages = 8) sized from every orbit's "
    "and encounter's time scale; no sim.dt needed. Meant for eccentric orbits and hierarchies, "
    "where REBOUND users reach for IAS15. epsilon (default " PFVI_STR(PFVI_EPSILON_DEFAULT) ") is the "
    "position error allowed per orbit, relative to the orbit: on the project's 13 comparison "
    "pages the default ends 5e2 to 2e6 times IAS15's default error (IAS15 epsilon 1e-9), at "
    "0.09-0.22 times its wall time. To compare with IAS15 at its default accuracy, set "
    "sim.integrator.epsilon = 1e-12: within a factor 9.8 of IAS15's default error on all 13 "
    "pages (7 at or below it), at 0.20-0.50 times its wall time. Every option and statistic is "
    "under Attributes below; the method follows.\n\n"
    "PFVI: phase-fitted discrete Lagrangian (variational) integrator of O. T. Kosmas and "
    "D. S. Vlachos, \"Phase-fitted Discrete Lagrangian Integrators\" (below: K&V). The discrete "
    "Lagrangian Ld = h sum_j w_j L(q^j, qdot^j) interpolates each particle's path "
    "with trigonometric functions fitted to a local frequency omega, so that the "
    "harmonic oscillator at omega is integrated exactly (fitting 'phase' at two nodes, "
    "'exact' at every s; off by default: 'none'). The frequency is estimated from the "
    "orbit (the pull of its partner, the curvature of the path, the osculating mean "
    "motion) or given, about a centre (the particle's pair barycentre by default, or K&V's "
    "coordinate origin). Steps are the position-momentum "
    "form p_k = -D1 Ld, p_k+1 = D2 Ld (Marsden & West 2001, Acta Numerica 10, 357). "
    "With two nodes (stages = 2) the step is explicit and second order, needs one "
    "force evaluation (the acceleration at the end of a step is reused at the start "
    "of the next), and with fitting = 'none' is exactly velocity Verlet. With s = 3 "
    "to " PFVI_STR(PFVI_STAGES_MAX) " Gauss-Lobatto nodes and interior corrections (K&V, 'Increasing the algebraic "
    "order'; Marsden & West 2001, section 2.6) the order is 2s - 2 and each step solves for the stage "
    "points by rounds corrected with Newton's method on each body's partner's pull (a simplified "
    "Newton iteration as in Antonana, Makazaga & Murua 2018, Numer. Algorithms 78, 63), from each "
    "body's two-body orbit about its partner, stopped when the measured rate of convergence says "
    "the doubles' resolution is reached and one more round confirms it; a solve that still does "
    "not converge (its change growing after the Jacobians were refreshed and dropped), or that meets "
    "a force that is not finite at a stage point, is retried shorter (n_solve_halved) or, where no "
    "shorter step is left, refused. Where "
    "omega = 0 (fitting 'none', the default) the step is Lobatto IIIA-IIIB in Runge-Kutta-"
    "Nystrom form with coefficients on which its symplecticity and symmetry hold exactly in "
    "doubles, and x, v and t advance by compensated sums, so that round-off grows like a "
    "random walk (Brouwer's law; Hairer, McLachlan & Razakarivony 2008, BIT 48, 231). "
    "Steps are adaptive by default (epsilon = " PFVI_STR(PFVI_EPSILON_DEFAULT) ", step_control = "
    "'symmetric'): h = kappa/rho with rho tracking a density of every orbit's and every encounter's "
    "time scale time-symmetrically (Hairer & Soderlind 2005), one stage solve per step, checked "
    "afterwards by the resolution of the step's own stages; epsilon is the relative position error "
    "per orbit; K&V's osculating-circle bound ('Frequency Evaluation and Error Control') "
    "is kept as step_control = 'reversible' or 'seed'; epsilon = 0 gives fixed steps of sim.dt, each "
    "checked by the same estimate (see epsilon). "
    "Forward or backward. A step that cannot be taken "
    "(invalid option, non-finite particle or force, overflow, u at a pole) raises an error "
    "and leaves t and every particle bit-identical; if a force callback added or removed "
    "particles during the step, t and every particle still present are restored and the "
    "error says how many were removed or added. Changes of the force model between "
    "integrate() or steps() calls or in a heartbeat act from the next step on, exactly as "
    "a fresh integrate() from that state. Options are checked, by name, when the next step "
    "starts (REBOUND offers no hook on assignment): a bad value makes integrate() raise and "
    "changes nothing. Variational particles (sim.add_variation(), first and second order, of test "
    "particles, of masses; sim.init_megno(); gravity 'basic', forces of positions alone) are stepped "
    "by the tangent map of each step: the same stages and fitted coefficients (the centre and omega "
    "frozen over the step), their forces REBOUND's variational accelerations at their tangent stage "
    "points, evaluated in the same calls as the real forces; the step sizes and every check come "
    "from the real particles only, whose trajectory is bit-identical with or without them. MEGNO "
    "and the Lyapunov exponent go through REBOUND's own update, with each step's integral taken by "
    "parts over its stages. Derivations and measurements: the docs/ folder of rebound_pfvi's source."
    ,
    .step = pfvi_step,
    .synchronize = pfvi_synchronize,
    .create = pfvi_create,
    .free = pfvi_free,
    .did_add_particle = pfvi_did_add_particle,
    .will_remove_particle = pfvi_will_remove_particle,
    .field_descriptor_list = pfvi_field_descriptor_list,
};

#define PFVI_ENUM_DESCRIPTOR(symbol, value, name) { value, name },
static struct reb_binarydata_enum_descriptor pfvi_fitting_enum[] = { PFVI_FITTINGS(PFVI_ENUM_DESCRIPTOR) { 0 } };
static struct reb_binarydata_enum_descriptor pfvi_frequency_enum[] = { PFVI_FREQUENCIES(PFVI_ENUM_DESCRIPTOR) { 0 } };
static struct reb_binarydata_enum_descriptor pfvi_step_control_enum[] = { PFVI_STEP_CONTROLS(PFVI_ENUM_DESCRIPTOR) { 0 } };
static struct reb_binarydata_enum_descriptor pfvi_centre_enum[] = { PFVI_CENTRES(PFVI_ENUM_DESCRIPTOR) { 0 } };
#undef PFVI_ENUM_DESCRIPTOR

// A field of the state: its documentation, REBOUND type, and member of
// struct pfvi_state, named after its last part.
#define PFVI_FIELD(doc, dtype, group, name) \
    { doc, dtype, #name, offsetof(struct pfvi_state, group.name), 0, 0, 0 }
#define PFVI_OPTION(doc, dtype, name) PFVI_FIELD(doc, dtype, settings, name)
#define PFVI_STATISTIC(doc, dtype, name) PFVI_FIELD("Statistic: " doc, dtype, statistics, name)

static const struct reb_binarydata_field_descriptor pfvi_field_descriptor_list[] = {
    { "Fitting of the discrete Lagrangian. 'none' (default): the classical trapezoidal Ld of "
      "Marsden & West (velocity Verlet), and for stages >= 3 the classical Lobatto Ld; under the "
      "adaptive step control (the default) fitting changes neither the steps nor the error and "
      "costs time (measured: the docs of rebound_pfvi's source), so it is off. 'phase': K&V's phase-fitted "
      "Ld divided by gamma(u) = u cot u, which makes positions and momenta exact on the "
      "harmonic oscillator with two nodes, but not for stages >= 3 (the interior corrections, "
      "polynomial, move the stage points off the oscillator's path). 'exact': 'phase' with each "
      "interior column of the differentiation matrix corrected (least norm) so that the "
      "stationarity equations hold on the oscillator's exact path: exact on the oscillator at "
      "every s, of order 2s - 2, and the same as 'phase' at s = 2. 'phase-literal': Ld exactly as "
      "printed by K&V; positions are exact on the oscillator (two nodes) but momenta come out "
      "scaled by gamma(u). With fixed steps 'exact' about partners pays "
      "(same docs, 'What fitting buys'). The seed's schemes as printed are 'phase' and "
      "'phase-literal' with centre = 'origin' and frequency = 'curvature'. "
      "Type: text (REBOUND lists its storage type). Default 'none'.",
      REB_INT, "fitting", offsetof(struct pfvi_state, settings.fitting), 0, 0, pfvi_fitting_enum },
    { "Source of the frequency omega, per particle, at the start of each step, from its "
      "position d and velocity w relative to its centre (see centre) and its acceleration a. "
      "With the centre 'partner', a is the partner's attraction: the frequencies are the pair's. "
      "'mean-motion' (default): the mean motion "
      "sqrt(mu/A^3) of the osculating two-body orbit about the particle's partner (see "
      "centre; mu = G (m + m_partner)), a constant of the unperturbed two-body motion; 0 if "
      "unbound or without a partner: no energy drift with fixed steps, and the most accurate in a "
      "hierarchy (same docs). 'radial': sqrt(-a.d)/|d|, so that the harmonic part -omega^2 d carries the whole "
      "pull towards the centre at the step's start (about a partner, G (m + m_partner)/r^3: its "
      "whole attraction); 0 if a points away from it: the most accurate on two bodies with fixed "
      "steps, but it drifts in energy at high e (same docs). 'curvature' (K&V, 'Frequency Evaluation and Error Control'): "
      "|w x a|/|w|^2, the angular rate on the osculating circle; 0 on a straight line or at rest. "
      "'fixed': the field omega, for every "
      "particle. Type: text. Default 'mean-motion'.",
      REB_INT, "frequency", offsetof(struct pfvi_state, settings.frequency), 0, 0, pfvi_frequency_enum },
    { "The centre of each particle's harmonic model: the fitted interpolation is applied to "
      "d = q - c(t), with c moving over the step from its position, velocity and acceleration at "
      "the start. 'partner' (default): the barycentre of the particle and its partner, the body j of "
      "largest G (m + m_j)/r^3 (the tightest pair: a moon's planet, a star's planet, a planet's "
      "star or its moon), falling with the pair's acceleration over the step, so that d sees the "
      "partner and the tide only; frame-free, and exact for both bodies of a circular pair. "
      "'barycentre': the barycentre of the massive bodies, uniformly moving (frame-free). 'origin' "
      "(K&V): the coordinate origin, at rest, so the step depends on the inertial frame. With "
      "gravity off, G = 0 or no other massive body (an external field) a particle's centre is the "
      "origin. Not used with fitting 'none'. Type: text. Default 'partner'.",
      REB_INT, "centre", offsetof(struct pfvi_state, settings.centre), 0, 0, pfvi_centre_enum },
    PFVI_OPTION("Frequency used when frequency = 'fixed' (code units of 1/time, finite, >= 0: checked "
        "whatever the frequency, so a bad value is refused at the next step, not when 'fixed' reads it). A fitted "
        "step far from the motion's frequency adds a repulsive force it does not show: each step with a "
        "fixed omega is checked on every particle's pull towards its centre and refused, naming the "
        "particle, where a deviation would grow. Default 0.",
        REB_DOUBLE, omega),
    PFVI_OPTION("Number s of Gauss-Lobatto nodes of the discrete Lagrangian, an integer from "
        PFVI_STR(PFVI_STAGES_MIN) " to " PFVI_STR(PFVI_STAGES_MAX) "; the order is "
        "2s - 2. s = 2: nodes 0 and 1, an explicit step with one force evaluation; with "
        "'phase' about the origin it is unstable for a body whose force ignores its own position "
        "(the star in a centre-of-mass frame: its offset from the origin grows by 1/cos u per step); "
        "about its partner (centre 'partner') it is not. s = 8 (default): order 14, the fastest at "
        "equal error under the symmetric step control from position errors of about 1e-7 of the orbit "
        "down (s = 6 is as fast at 1e-6; docs of rebound_pfvi's source). s >= 3: interior corrections delta q^j made stationary "
        "(K&V, 'Increasing the algebraic order'). The stage equations are solved by rounds, each "
        "evaluating the forces at the stage points and corrected by Newton's method with each "
        "body's partner's tidal pull (mutual partners in their relative coordinate), from each "
        "body's two-body orbit about its partner; they stop by the measured rate of convergence, "
        "with one confirming round (about 3 to 4 rounds of s - 2 force evaluations, plus one at "
        "the step's end; s per round if forces depend on velocities), at most "
        PFVI_STR(PFVI_ITERATION_MAX) " rounds per step (rebound_pfvi's docs, the stage solve). "
        "Default " PFVI_STR(PFVI_STAGES_DEFAULT) ".",
        REB_INT, stages),
    PFVI_OPTION("Largest |u| = omega*|dt| used in the fitted coefficients; a larger value is "
        "limited to u_max and counted in n_u_limited. Must lie in (0, pi). The two-point "
        "coefficients have a pole at u = pi/2 (and, for 'phase-literal', at pi): a step whose "
        "u lies within " PFVI_STR(PFVI_POLE_GUARD) " of one is refused. Default "
        PFVI_STR(PFVI_U_MAX_DEFAULT) ", where tan(u)/u = 1.56. For s >= 3 "
        "the stage matrix is regular on (0, pi) except for s = 4 at u = 2.857; steps where its "
        "determinant falls below " PFVI_STR(PFVI_POLE_GUARD) " of its value at u = 0 are refused.",
        REB_DOUBLE, u_max),
    PFVI_OPTION("Tolerance of the adaptive step control; 0: fixed steps of sim.dt. Default "
        PFVI_STR(PFVI_EPSILON_DEFAULT) ". With step_control = 'symmetric' (default) it is the "
        "position error per orbit a body may gather, relative to its orbit's size: measured, every "
        "body's error ends within 3.4 times epsilon a n (a its orbit's size, n its orbits), mostly far below, on "
        "Kepler orbits of e = 0.5 ... 0.99, a comet passing Jupiter, a body crossing Jupiter's orbit, "
        "a sungrazer, a circumbinary planet, the outer solar system and a periodic box; over Kepler pairs "
        "of e = 0.1 ... 0.95 from 8 phases, 100 orbits, within 0.53 times at the default and 0.9 at 1e-9 "
        "... 3e-8, but 11.6 and 7.7 at 1e-7 and 1e-8 where an orbit takes within a few hundredths of a "
        "whole number of steps and the orbits' errors add up (off that grid, 10 at 1e-7 over 100 orbits of e = 0.70 "
        "at 10.01 steps an orbit, 16 at its worst output; rebound_pfvi's docs, step control). Steps are kappa/rho with kappa = (epsilon/C_s)^(1/(2s - 2)) and rho "
        "following a density of the system's time scales (see step_control). Epsilon is held within "
        "what s stages deliver: above C_s " PFVI_STR(PFVI_KAPPA_MAX) "^(2s - 2) (s = 8: 1.2e-7, s = 6: 4.4e-5, "
        "s = 4: 0.019) kappa is at its cap of " PFVI_STR(PFVI_KAPPA_MAX) " (the stage solve converges "
        "far beyond it; the step track's time symmetry does not yet: rebound_pfvi's docs, the stage "
        "solve) and the error stays below the request; below the round-off floor (s = 5 ... 8: 1e-14, s = 4: 1e-13, "
        "s = 3: 1e-12, s = 2: 1e-10) the error per orbit stops falling and the request is taken as the "
        "floor (epsilon_effective says what was used); on near-radial orbits the floor is higher: s = 8 "
        "ends within 9.5 and 93 times epsilon a n at 1e-12 on e = 0.99 and 0.999 (IAS15: 6.2 and 1070). Where kappa is below " PFVI_STR(PFVI_KAPPA_WARN) " (s = 2 "
        "below epsilon 1.4e-7) REBOUND warns, once per simulation, with the steps an orbit takes, about "
        "2 pi/kappa on a circle and more where it is eccentric (s = 2 at 1e-10: 2.6e6 at e = 0, 7e7 at "
        "e = 0.9), and the steps 8 stages take. With 'reversible' and 'seed' it bounds "
        "K&V's osculating-circle estimate | |R1 - R2| - |O1 - O2| | of a step's position error, "
        "relative to the smaller radius, for the particle where it is largest: third order in dt "
        "whatever the order of the scheme; a particle without comparable circles at both ends (at "
        "rest, on a radial path, across an inflection) is left out, and with none left the step is "
        "held at most sim.dt. Those two also keep u = omega*|dt| <= u_max. With epsilon = 0 every "
        "fixed step is checked as the symmetric control checks its steps: the error per orbit its stages "
        "imply (for a fitted step, from the force its fitted path does not carry, a + omega^2 d). Above "
        PFVI_STR(PFVI_FIXED_WARN) " REBOUND warns, once per simulation, naming the particle, the step and "
        "that error (at s = 2 it runs 5 to 25 times above the error measured on Kepler orbits: 50 steps per "
        "period warn there, not at s >= 4). Where that estimate saturates (a step across a pericentre it "
        "does not resolve) it warns too if the step spans more of the fastest orbit than steps that err by "
        PFVI_STR(PFVI_FIXED_WARN) " per orbit (s = 8: 2.2 radians), or, without pairs to measure it against, "
        "at once; a step longer than " PFVI_STR(PFVI_FIXED_KAPPA_MAX) " over the "
        "step density (more than an orbit of the fastest time scale, where the stage solve can converge to "
        "no motion at all: measured 20 to 600 AU off after three steps) is refused, state restored.",
        REB_DOUBLE, epsilon),
    { "Step selection when epsilon > 0. 'symmetric' (default): h = kappa/rho with rho following a "
      "density sigma of the system's time scales: per body the frequency of its osculating orbit about "
      "the subsystem it orbits (its partner, the tightest pair it is in, and what that partner is bound "
      "to more tightly: a circumbinary planet orbits the binary), and per unbound pair (or ghost image) "
      "its crossing rate v/r, softened, weighted by (R/(1+R))^(1/(2s-2)) where neither body is the "
      "other's partner (R: the pair's pull on each body against its partner's; two planets about a star "
      "have R ~ 1e-3 and no time scale of their own); rho_n+1/2 = rho_n-1/2 + kappa d log(sigma)/dt (Hairer & "
      "Soderlind 2005, SIAM J. Sci. Comput. 26, 1838) reads the same forward and backward: one stage "
      "solve per step, and a round trip retraces the steps: sim.steps(n), sim.dt = -sim.dt, "
      "sim.steps(n) comes back to the start, and so does integrate(T) then integrate(0) (the track's "
      "drift average counts each interval once, so a reversal does not fire it anew; a requested time "
      "within " PFVI_STR(PFVI_OUTPUT_NEAR) " of the run's span (and " PFVI_STR(PFVI_OUTPUT_NEAR_ULPS) " of t's last "
      "places) from the state reached is taken as reached). A steady density holds the track: with " PFVI_STR(PFVI_STEADY_BODIES) " or more bodies, "
      "where the density at the ends of at least " PFVI_STR(PFVI_STEADY_WINDOW) " intervals in a row, spanning "
      "a cycle of the slowest orbit (2 pi/sqrt(G (m_i + m_j)/r^3) of the loosest partner pair), stayed "
      "within a factor 1 + " PFVI_STR(PFVI_STEADY_BAND) " (a planetary system of low eccentricities), rho "
      "is held once it reaches the largest of them and the steps are constant, so that the classical "
      "step's symplecticity keeps the energy bounded (a varying track does not); the hold ends where the "
      "density at an interval's end rises above rho (1 + " PFVI_STR(PFVI_STEADY_EXCESS) ") (the track goes "
      "on from rho) or falls below rho/(1 + " PFVI_STR(PFVI_STEADY_BAND) ") (rho moves onto it: counted in "
      "n_asymmetric). A reversal undoes the last start and end of a hold where the way out made them. "
      "Outputs do not change the run: where REBOUND finishes on a requested time "
      "(integrate(t) with exact_finish_time = 1, its default) the step takes its whole interval and "
      "the simulation is given the state at t from an output step, one trial step from the step's "
      "end back to t, never committed (n_outputs); the run's own state is kept (saved in archives) "
      "and the next step goes on from it if the simulation was not edited (particles, t, N, stages, "
      "epsilon or the force model; variational particles rescaled by REBOUND count as unedited), so "
      "a run's steps and states do not depend on its output times, and an output's error is the "
      "run's plus that of one step shorter than its own. A step longer than sim.dt (a new "
      "simulation's first), or the run's end taken up after an output (further than the proposal "
      "in sim.dt where the steps shorten), that would pass the time Python's "
      "sim.integrate(t) asked for shows t itself, as a finishing step would: no hook, collision "
      "search, Encounter or Escape check sees a state past t (REBOUND's C reb_simulation_integrate, "
      "called directly, does not tell pfvi t). A time on one of the run's step ends is "
      "the run's own state; the sim.dt REBOUND sets back after integrate() (its last full step, or "
      "the value the call began with) is told from one the user sets, and does not cap the next "
      "call (a sim.steps() right after a new simulation's first integrate() takes REBOUND's 0.001 "
      "there for a cap). REBOUND's boundary (a periodic box's wrap, an open box's removal of a body "
      "that left it) is applied to the run's own state where a single call has it: a body an open "
      "box lost by a step's end is gone from an output inside that step too. "
      "An edit makes the shown state the user's, "
      "as after any edit. Forces beyond the fields (additional_forces, REBOUNDx's forces and their "
      "parameters, custom gravity) are evaluated once more at the run's state when a call takes it up "
      "(with velocity-dependent forces also when the output is shown): if they changed between the "
      "calls (a callback's own variables, a REBOUNDx force added, removed or given a new parameter), "
      "the output is taken as edited and the run goes on from it. A contact search set between the "
      "calls (exit_min_distance, collisions, a radius) does the same. MEGNO's "
      "Y is the output's; <Y> and the Lyapunov exponent are sampled at the run's steps. "
      "Hooks an output step cannot keep consistent with the state it shows fall back to steps cut "
      "at the requested times, as REBOUND's other integrators do: with ODEs (sim.create_ode, "
      "REBOUNDx's tides_spin among them) or pre- or post-timestep modifications (REBOUNDx operators "
      "among them) set, the step ends on each requested time, the ODEs are integrated and the "
      "modifications fired over exactly the time the state shown has lived (dt_last_done), and the "
      "run's steps depend on the output times. "
      "exact_finish_time = 0, fixed steps (epsilon = 0) and fittings other than 'none' are as "
      "before: sim.dt is the step proposed after each step; a different value (REBOUND finishing on "
      "time where outputs are not shown, the user) caps the step "
      "and the next steps cross the rest of the interval, so the track goes on and a reversal "
      "retraces the capped step first. REBOUND's sim.dt of a new simulation (0.001) does not cap the "
      "first step; any other value set before it does. Checks at each step's end, each retaking the "
      "step shorter (n_rejected; such steps are not time-symmetric: n_asymmetric): a stage solve that "
      "does not converge (half the step); a density at either end above "
      PFVI_STR(PFVI_DENSITY_JUMP_MAX) " times kappa/h (a close approach within one step: half the "
      "step); stage accelerations whose polynomial shows the forces resolved worse than on any Kepler "
      "orbit (the error they imply above " PFVI_STR(PFVI_RESOLUTION_MAX) " times the worst there: a "
      "time scale the density does not show, such as a force callback's): retaken at the step that "
      "resolves them, the density scaled up (density_scale) and let down again where the steps turn "
      "out finer than needed. A force that jumps within a step (a tree code's cells) is resolved by "
      "no step: after " PFVI_STR(PFVI_RESOLUTION_RETRIES) " retakes the step is kept and counted in "
      "n_unresolved. A whole interval (a step as the track began it) that the density outran, its "
      "density at an end above " PFVI_STR(PFVI_SPLIT_DENSITY) " times what the step was sized for "
      "(kappa/(density_scale h)) and its stages resolving the forces worse than "
      PFVI_STR(PFVI_SPLIT_RESOLUTION) " of the Kepler worst, is crossed in two halves (a comet falling "
      "in from under a planet's time scale): counted in n_rejected, but time-symmetric, since a "
      "reversal meets the same interval from its other end and splits it the same way; the track "
      "and its grid are unchanged. "
      "Without pairs (gravity off, or no massive body: test particles in a potential from "
      "additional_forces) there is no density: each step is sized from its own stages' resolution u "
      "of the forces, aimed at a_s kappa for s stages (a circular orbit's u under the density is kappa; a_s = "
      PFVI_STR_LIST(PFVI_UNPAIRED_AIMS_2_TO_8) " for s = 2 ... 8: fewer stages see less of a pericentre passage) and retaken above " PFVI_STR(PFVI_UNPAIRED_RETAKE) " times that; these steps "
      "are not time-symmetric (n_asymmetric). A body's resolution is measured against its largest "
      "stage acceleration and, once a step was retaken, against epsilon |v|/|h| (a force that vanishes at the edge of its "
      "region reads the same at any step ending there, but its kick cannot move the body by epsilon "
      "of its path); a step so resolved only against the motion grows no further than the force's "
      "own scale, or free motion, allows. Forces that do not vary over a step (free motion, a uniform field) keep the "
      "step, or grow it back (at most " PFVI_STR(PFVI_CONTROL_GROW_MAX) "x a step) to the longest "
      "such step the run took (sim.dt at the start), never beyond, so as not to leap a force region; "
      "where nothing can act (no pair gravity joins: G = 0, gravity off, one body or no active mass; no "
      "additional force, no timestep hook and no ghost boxes) they grow " PFVI_STR(PFVI_CONTROL_GROW_MAX) "x a step without "
      "bound, as IAS15's do (contacts are still found inside them); "
      "a sim.dt below the run's proposal (REBOUND's cut to a requested time, the value it restores "
      "after one, the user's) caps one step, and the next is grown from the proposal. "
      "'seed' (K&V): a step is accepted if the osculating-circle estimate "
      "is at most epsilon, otherwise retried shorter (counted in n_rejected, nothing changed); "
      "the next step is h*" PFVI_STR(PFVI_CONTROL_SAFETY) "*(epsilon/estimate)^(1/"
      PFVI_STR(PFVI_CONTROL_ORDER) "), at most " PFVI_STR(PFVI_CONTROL_GROW_MAX) "x and at least "
      PFVI_STR(PFVI_CONTROL_SHRINK_MIN) "x larger; a step rejected " PFVI_STR(PFVI_CONTROL_MAX_REJECTIONS)
      " times is refused. 'reversible': each step solves estimate(start, end) = epsilon (or "
      "u = u_max) for h, fitted to the mean of the curvature frequencies at its two ends, as in "
      "Hut, Makino & McMillan 1995 (ApJ 443, L93); it costs about 3 to 5 trial steps per step "
      "(n_attempts), and near pericentre and apocentre the two directions may pick different "
      "steps. With 'seed' and 'reversible' epsilon bounds each step's estimate, not the error, which "
      "adds up over the steps: after 3 orbits of Kepler e = 0.99 at s = 2 and epsilon 1e-6 they end "
      "0.88 and 1.5 off (e = 0.5: 0.012, 0.014), 'symmetric' 1.2e-6 (against IAS15: benchmarks/"
      "step_controls_error.py). "
      "Type: text. Default 'symmetric'.",
      REB_INT, "step_control", offsetof(struct pfvi_state, settings.step_control), 0, 0, pfvi_step_control_enum },
    { "", REB_POINTER, "compensation", offsetof(struct pfvi_state, compensation),
        offsetof(struct pfvi_state, N_compensation), sizeof(struct pfvi_compensation), 0 },
    { "", REB_POINTER, "end_state", offsetof(struct pfvi_state, end),
        offsetof(struct pfvi_state, end_length), sizeof(struct pfvi_end_state), 0 },
    { "", REB_POINTER, "stage_accelerations", offsetof(struct pfvi_state, predictor_a),
        offsetof(struct pfvi_state, predictor_length), sizeof(*((struct pfvi_state*)0)->predictor_a), 0 },
    { "", REB_POINTER, "stage_positions", offsetof(struct pfvi_state, predictor_x),
        offsetof(struct pfvi_state, predictor_length), sizeof(*((struct pfvi_state*)0)->predictor_x), 0 },
    { "", REB_POINTER, "variational_stage_accelerations", offsetof(struct pfvi_state, var_predictor_a),
        offsetof(struct pfvi_state, var_predictor_length), sizeof(*((struct pfvi_state*)0)->var_predictor_a), 0 },
    { "", REB_POINTER, "variational_stage_positions", offsetof(struct pfvi_state, var_predictor_x),
        offsetof(struct pfvi_state, var_predictor_length), sizeof(*((struct pfvi_state*)0)->var_predictor_x), 0 },
    { "", REB_UINT64, "end_state_count", offsetof(struct pfvi_state, end_saved_N), 0, 0, 0 },
    { "", REB_UINT64, "stage_count", offsetof(struct pfvi_state, predictor_N), 0, 0, 0 },
    { "", REB_UINT64, "variational_stage_count", offsetof(struct pfvi_state, var_predictor_N), 0, 0, 0 },
    { "", REB_INT, "counts_saved", offsetof(struct pfvi_state, counts_saved), 0, 0, 0 },
    { "", REB_DOUBLE, "dt_reversible", offsetof(struct pfvi_state, dt_reversible), 0, 0, 0 },
    { "", REB_INT, "unpaired_suspect", offsetof(struct pfvi_state, unpaired_suspect), 0, 0, 0 },
    { "", REB_DOUBLE, "dt_suspect", offsetof(struct pfvi_state, dt_suspect), 0, 0, 0 },
    { "", REB_INT, "suspect_body", offsetof(struct pfvi_state, suspect_body), 0, 0, 0 },
    { "", REB_DOUBLE, "dt_free", offsetof(struct pfvi_state, dt_free), 0, 0, 0 },
    { "", REB_INT, "unpaired_retaken", offsetof(struct pfvi_state, unpaired_retaken), 0, 0, 0 },
    { "", REB_INT, "unpaired_crawl", offsetof(struct pfvi_state, unpaired_crawl), 0, 0, 0 },
    { "", REB_DOUBLE, "rho", offsetof(struct pfvi_state, rho), 0, 0, 0 },
    { "", REB_DOUBLE, "rho_sign", offsetof(struct pfvi_state, rho_sign), 0, 0, 0 },
    { "", REB_DOUBLE, "dt_proposed", offsetof(struct pfvi_state, dt_proposed), 0, 0, 0 },
    { "", REB_DOUBLE, "track_done", offsetof(struct pfvi_state, track_done), 0, 0, 0 },
    { "", REB_INT, "track_at_end", offsetof(struct pfvi_state, track_at_end), 0, 0, 0 },
    { "", REB_DOUBLE, "track_mismatch", offsetof(struct pfvi_state, track_mismatch), 0, 0, 0 },
    { "", REB_DOUBLE, "track_seen_lo", offsetof(struct pfvi_state, track_seen_lo), 0, 0, 0 },
    { "", REB_DOUBLE, "track_seen_hi", offsetof(struct pfvi_state, track_seen_hi), 0, 0, 0 },
    { "", REB_INT, "track_edited_before", offsetof(struct pfvi_state, track_edited_before), 0, 0, 0 },
    { "", REB_INT, "track_restarted", offsetof(struct pfvi_state, track_restarted), 0, 0, 0 },
    { "", REB_INT, "steady_hold", offsetof(struct pfvi_state, steady.hold), 0, 0, 0 },
    { "", REB_INT, "steady_n", offsetof(struct pfvi_state, steady.n), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_lo", offsetof(struct pfvi_state, steady.lo), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_hi", offsetof(struct pfvi_state, steady.hi), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_t0", offsetof(struct pfvi_state, steady.t0), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_span", offsetof(struct pfvi_state, steady.span), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_entry_t", offsetof(struct pfvi_state, steady.entry_t), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_entry_sign", offsetof(struct pfvi_state, steady.entry_sign), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_entry_rho", offsetof(struct pfvi_state, steady.entry_rho), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_exit_t", offsetof(struct pfvi_state, steady.exit_t), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_exit_sign", offsetof(struct pfvi_state, steady.exit_sign), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_exit_held", offsetof(struct pfvi_state, steady.exit_held), 0, 0, 0 },
    { "", REB_DOUBLE, "steady_exit_after", offsetof(struct pfvi_state, steady.exit_after), 0, 0, 0 },
    { "", REB_DOUBLE, "track_kappa", offsetof(struct pfvi_state, track_kappa), 0, 0, 0 },
    { "", REB_DOUBLE, "density_scale", offsetof(struct pfvi_state, density_scale), 0, 0, 0 },
    { "", REB_DOUBLE, "dt_last_full", offsetof(struct pfvi_state, dt_last_full), 0, 0, 0 },
    { "", REB_DOUBLE, "t_compensation", offsetof(struct pfvi_state, t_compensation), 0, 0, 0 },
    { "", REB_DOUBLE, "t_compensated", offsetof(struct pfvi_state, t_compensated), 0, 0, 0 },
    { "", REB_POINTER, "output_real", offsetof(struct pfvi_state, output_real),
        offsetof(struct pfvi_state, output_saved_N), sizeof(struct pfvi_output_particle), 0 },
    { "", REB_POINTER, "output_shown", offsetof(struct pfvi_state, output_shown),
        offsetof(struct pfvi_state, output_saved_N), sizeof(struct pfvi_output_particle), 0 },
    { "", REB_POINTER, "output_var_real", offsetof(struct pfvi_state, output_var_real),
        offsetof(struct pfvi_state, output_var_saved_N), sizeof(struct pfvi_output_particle), 0 },
    { "", REB_POINTER, "output_var_shown", offsetof(struct pfvi_state, output_var_shown),
        offsetof(struct pfvi_state, output_var_saved_N), sizeof(struct pfvi_output_particle), 0 },
    { "", REB_UINT64, "output_count", offsetof(struct pfvi_state, output_N), 0, 0, 0 },
    { "", REB_UINT64, "output_var_count", offsetof(struct pfvi_state, output_var_N), 0, 0, 0 },
    { "", REB_POINTER, "output_check", offsetof(struct pfvi_state, output_check),
        offsetof(struct pfvi_state, output_check_N), sizeof(struct pfvi_output_check), 0 },
    { "", REB_DOUBLE, "output_exit_min_distance", offsetof(struct pfvi_state, output_exit_min_distance), 0, 0, 0 },
    { "", REB_INT, "output_collision", offsetof(struct pfvi_state, output_collision), 0, 0, 0 },
    { "", REB_DOUBLE, "output_megno_Ys", offsetof(struct pfvi_state, output_megno[0][0]), 0, 0, 0 },
    { "", REB_DOUBLE, "output_megno_Yss", offsetof(struct pfvi_state, output_megno[0][1]), 0, 0, 0 },
    { "", REB_DOUBLE, "output_megno_Ys_shown", offsetof(struct pfvi_state, output_megno[1][0]), 0, 0, 0 },
    { "", REB_DOUBLE, "output_megno_Yss_shown", offsetof(struct pfvi_state, output_megno[1][1]), 0, 0, 0 },
    { "", REB_DOUBLE, "output_t", offsetof(struct pfvi_state, output_t), 0, 0, 0 },
    { "", REB_DOUBLE, "output_t_real", offsetof(struct pfvi_state, output_t_real), 0, 0, 0 },
    { "", REB_INT, "output_stages", offsetof(struct pfvi_state, output_stages), 0, 0, 0 },
    { "", REB_DOUBLE, "output_epsilon", offsetof(struct pfvi_state, output_epsilon), 0, 0, 0 },
    // The numbers of the shown output's force model (pfvi_force_model_kept).
#define PFVI_MODEL_DOUBLE(field, member) \
    { "", REB_DOUBLE, "output_model_" #member, offsetof(struct pfvi_state, output_model.field), 0, 0, 0 },
#define PFVI_MODEL_SIZE(field, member) \
    { "", REB_UINT64, "output_model_" #member, offsetof(struct pfvi_state, output_model.field), 0, 0, 0 },
#define PFVI_MODEL_INT(field, member) \
    { "", REB_INT, "output_model_" #member, offsetof(struct pfvi_state, output_model.field), 0, 0, 0 },
#define PFVI_MODEL_POINTER(field, member)
    PFVI_FORCE_MODEL_FIELDS(PFVI_MODEL_DOUBLE, PFVI_MODEL_SIZE, PFVI_MODEL_INT, PFVI_MODEL_POINTER)
#undef PFVI_MODEL_DOUBLE
#undef PFVI_MODEL_SIZE
#undef PFVI_MODEL_INT
#undef PFVI_MODEL_POINTER
    { "", REB_INT, "output_model_saved", offsetof(struct pfvi_state, output_model_saved), 0, 0, 0 },
    { "", REB_DOUBLE, "output_last_t0", offsetof(struct pfvi_state, output_last_t0), 0, 0, 0 },
    { "", REB_DOUBLE, "output_last_t1", offsetof(struct pfvi_state, output_last_t1), 0, 0, 0 },
    // (The values REBOUND restores sim.dt to after integrate(), pfvi_step:
    // a copy or restart tells them from a user's sim.dt as the run did.)
    { "", REB_DOUBLE, "dt_rebound_leaves", offsetof(struct pfvi_state, dt_rebound_leaves), 0, 0, 0 },
    { "", REB_DOUBLE, "dt_call_began", offsetof(struct pfvi_state, dt_call_began), 0, 0, 0 },
    { "", REB_INT, "dt_call_default", offsetof(struct pfvi_state, dt_call_default), 0, 0, 0 },
    { "", REB_INT, "dt_call_first_cut", offsetof(struct pfvi_state, dt_call_first_cut), 0, 0, 0 },
    { "", REB_DOUBLE, "dt_user", offsetof(struct pfvi_state, dt_user), 0, 0, 0 },
    { "", REB_INT, "dt_user_spent", offsetof(struct pfvi_state, dt_user_spent), 0, 0, 0 },
    { "", REB_INT, "in_call", offsetof(struct pfvi_state, in_call), 0, 0, 0 },
    { "", REB_DOUBLE, "dt_call_entry", offsetof(struct pfvi_state, dt_call_entry), 0, 0, 0 },
    { "", REB_DOUBLE, "dt_rebound_raw", offsetof(struct pfvi_state, dt_rebound_raw), 0, 0, 0 },
    { "", REB_DOUBLE, "request_dt_leaves", offsetof(struct pfvi_state, request_dt_leaves), 0, 0, 0 },
    { "", REB_INT, "request_loaded_cut", offsetof(struct pfvi_state, request_loaded_cut), 0, 0, 0 },
    { "", REB_DOUBLE, "request_dt_restore", offsetof(struct pfvi_state, request_dt_restore), 0, 0, 0 },
    { "", REB_DOUBLE, "dt_call_cut", offsetof(struct pfvi_state, dt_call_cut), 0, 0, 0 },
    { "", REB_INT, "last_finishing", offsetof(struct pfvi_state, last_finishing), 0, 0, 0 },
    { "", REB_INT, "predictor_stages", offsetof(struct pfvi_state, predictor_stages), 0, 0, 0 },
    { "", REB_DOUBLE, "predictor_h", offsetof(struct pfvi_state, predictor_h), 0, 0, 0 },
    { "", REB_DOUBLE, "predictor_t", offsetof(struct pfvi_state, predictor_t), 0, 0, 0 },
    { "", REB_INT, "contact_chain", offsetof(struct pfvi_state, contact_chain), 0, 0, 0 },
    { "", REB_INT, "output_contact_pending", offsetof(struct pfvi_state, output_contact_pending), 0, 0, 0 },
    PFVI_STATISTIC("steps taken by this integrator.", REB_UINT64, n_steps),
    PFVI_STATISTIC("particle-steps in which u = omega*dt exceeded u_max and was limited, "
        "or omega exceeded " PFVI_STR(PFVI_OMEGA_MAX) " (omega^2 beyond the doubles) and the particle "
        "was stepped unfitted.",
        REB_UINT64, n_u_limited),
    PFVI_STATISTIC("force evaluations (the forces at one point of a step: REBOUND's "
        "reb_simulation_update_acceleration, or where that would compute REBOUND's basic gravity, the same "
        "gravity from pfvi's own pass over every stage and the additional forces called beside it). A step "
        "reuses the last step's end acceleration only within one integrate() or steps() call, with no "
        "heartbeat or timestep hook set, no ODE beside a force callback, and nothing the force reads "
        "changed (particles, t, G, softening, N_active, "
        "testparticle_type, gravity mode, boundary, additional_forces, extras); otherwise it "
        "evaluates it afresh.",
        REB_UINT64, n_force_evaluations),
    PFVI_STATISTIC("iterations of the stage solve, summed over steps (1 per two-point step).",
        REB_UINT64, n_iterations),
    PFVI_STATISTIC("most iterations of the stage solve in one step.",
        REB_UINT64, iterations_max),
    PFVI_STATISTIC("n_iterations / n_steps.",
        REB_DOUBLE, iterations_mean),
    PFVI_STATISTIC("the epsilon the symmetric step control used for the last step: epsilon held "
        "within what the stages can deliver (0 before a symmetric step).",
        REB_DOUBLE, epsilon_effective),
    PFVI_STATISTIC("steps tried and rejected by the step control (or whose stage "
        "solve did not converge and was retried shorter; 'symmetric': see step_control).",
        REB_UINT64, n_rejected),
    PFVI_STATISTIC("trial steps, taken or not (the work done: n_attempts / n_steps per step).",
        REB_UINT64, n_attempts),
    PFVI_STATISTIC("steps taken that are not time-symmetric: 'symmetric' steps retaken shorter "
        "(see step_control), after which density_scale fell back, the track's drift correction acted, "
        "or a steady hold ended with a jump of rho, and 'reversible' "
        "steps whose step equation was not solved in " PFVI_STR(PFVI_REVERSIBLE_MAX_TRIALS) " trial "
        "steps and that were taken at the largest step tried meeting epsilon.",
        REB_UINT64, n_asymmetric),
    PFVI_STATISTIC("symmetric steps kept although their stages showed forces that a shorter "
        "step did not resolve better (forces that jump within a step, as a tree code's cells do); "
        "their error is not bounded by epsilon.", REB_UINT64, n_unresolved),
    PFVI_STATISTIC("the step control's error estimate for the last step taken (with fixed steps "
        "the stages' implied error per orbit, see epsilon). 'symmetric': from the stage accelerations, the error per orbit that a step "
        "resolving the forces this well makes where Kepler orbits are resolved worst: at most "
        "about epsilon_effective where the density sees every time scale.",
        REB_DOUBLE, error_estimate),
    PFVI_STATISTIC("force evaluations made for the variational particles alone: the rounds of their tangent "
        "solve after the real stage solve had converged (included in n_force_evaluations; the real "
        "particles' steps are the same with or without variational particles).",
        REB_UINT64, n_variational_evaluations),
    PFVI_STATISTIC("steps whose tangent solve of the variational particles stopped (changes no longer "
        "decreasing, or " PFVI_STR(PFVI_ITERATION_MAX) " rounds) above " PFVI_STR(PFVI_ITERATION_TOLERANCE)
        " (relative); their step is kept, since the real step never depends on them.",
        REB_UINT64, n_variational_unconverged),
    PFVI_STATISTIC("steps whose s-point stage solve saw its Newton correction fail (a change that grew, "
        "or a singular matrix) and went on with its Jacobians refreshed, or with the plain round "
        "(rebound_pfvi's docs, the stage solve); the step is then taken as any other.",
        REB_UINT64, n_solve_recovered),
    PFVI_STATISTIC("trial steps halved because their stage solve did not converge or met a force "
        "that is not finite at a stage point (included in n_rejected; with the symmetric control such "
        "a step is not time-symmetric).",
        REB_UINT64, n_solve_halved),
    PFVI_STATISTIC("output steps: states shown at a time REBOUND asked to finish on (integrate(t) with "
        "exact_finish_time = 1) that the step passed, each a trial step from the step's end back to "
        "that time, never committed (see step_control; none while ODEs or pre- or post-timestep "
        "modifications are set: the step is cut at the time instead). Not counted in n_steps or n_attempts; their "
        "force evaluations are in n_force_evaluations.",
        REB_UINT64, n_outputs),
    PFVI_STATISTIC("steps retaken to end at a contact inside them: with collisions on (sim.collision not "
        "'none') and a radius set (radii must then be finite and >= 0: a NaN or negative one is refused by "
        "name), or sim.exit_min_distance set, each step taken is searched for the first "
        "time two bodies come closer than the sum of their radii or exit_min_distance, along the "
        "polynomial through its stages (positions and accelerations at its nodes, velocities at its "
        "ends; candidate pairs by a bound from each body's nodes); the step is retaken to end there, "
        PFVI_STR(PFVI_CONTACT_DEPTH) " of the limit inside it (at most half the dip), so that REBOUND's "
        "collision search and resolve and its Encounter see the contact at the step's end. Outputs do "
        "not cut the searched steps: an output before the contact is shown from the retaken step, and "
        "REBOUND sees the contact once an output reaches it, as in a single call. With sim.collision "
        "'line' or 'linetree' (REBOUND's straight segments drawn back from each step's end over "
        "dt_last_done, which a curved step does not follow) a step whose segments come within the radii "
        "where its path does not is retaken at half its length until they agree (at most "
        PFVI_STR(PFVI_CONTACT_LINE_HALVINGS) " times), and a call that shows an output reports "
        "dt_last_done = 0, so that REBOUND looks at the state shown. Included in "
        "n_rejected and n_asymmetric; the steps are not time-symmetric (rebound_pfvi's docs, collisions).",
        REB_UINT64, n_contact_steps),
    PFVI_STATISTIC("steps kept past a contact their path showed, because " PFVI_STR(PFVI_CONTACT_RETAKES)
        " steps in a row had been retaken to end at a contact their end did not reach (a minimum "
        "separation within the step's error of the limit); they are kept until no contact is "
        "predicted.", REB_UINT64, n_contact_kept),
    PFVI_STATISTIC("smallest omega used in the last step (after limiting).",
        REB_DOUBLE, omega_min),
    PFVI_STATISTIC("largest omega used in the last step (after limiting).",
        REB_DOUBLE, omega_max),
    { 0 },
};

static void* pfvi_create(void){
    struct pfvi_state* st = calloc(1, sizeof(struct pfvi_state));
    struct pfvi_replay* replay = malloc(PFVI_REPLAY_MAX*sizeof(*replay));
    if (!st || !replay){
        free(st);
        free(replay);
        return NULL;
    }
    st->replay = replay;
    st->settings = (struct pfvi_options){
        .fitting = PFVI_FITTING_NONE,
        .frequency = PFVI_FREQUENCY_MEAN_MOTION,
        .stages = PFVI_STAGES_DEFAULT,
        .omega = 0.,
        .u_max = PFVI_U_MAX_DEFAULT,
        .epsilon = PFVI_EPSILON_DEFAULT,
        .step_control = PFVI_STEP_CONTROL_SYMMETRIC,
        .centre = PFVI_CENTRE_PARTNER,
    };
    st->options = st->settings;
    st->density_scale = 1.;
    st->track_at_end = 1;
    // No output step has failed: not 0, a time a run may end on (a way back
    // to the start: before, every output inside its last step was a step cut
    // short, a hyperbolic flyby's way back 4 steps against one call's 2).
    st->output_failed_t = NAN;
    return st;
}

static void pfvi_free(void* state){
    struct pfvi_state* const st = state;
    if (st && st->in_step != PFVI_STEP_IDLE){
        // A force callback (or heartbeat of a step in progress) switched or
        // re-assigned the integrator: the step still uses this state. It
        // ends as if the change had come after it; then the state goes.
        st->free_pending = 1;
        return;
    }
    if (st){
        pfvi_state_free(st);
    }
}

// The message for the fault a lower layer recorded.
static void pfvi_report(struct reb_simulation* r, const struct pfvi_state* st){
    const struct pfvi_fault* const f = &st->fault;
    switch (f->kind){
        case PFVI_FAULT_MEMORY:
            pfvi_error(r, "pfvi: could not allocate scratch memory for %zu particles.", f->n);
            break;
        case PFVI_FAULT_N_CHANGED:
            if (f->flag){
                pfvi_error(r, "pfvi: a callback changed the number of particles from %zu to %zu during the force "
                        "evaluation at t = %.17g; step not taken: t and the %zu particles still present are restored "
                        "to the step's start, %zu removed are gone, %zu added are kept.",
                        f->n, f->n_after, f->t, f->kept, f->n - f->kept, f->added);
            }else{
                pfvi_error(r, "pfvi: a callback changed the number of particles from %zu to %zu during the force "
                        "evaluation at t = %.17g; step not taken, t restored, but the particles could not be "
                        "(out of memory): they are left mid-step.", f->n, f->n_after, f->t);
            }
            break;
        case PFVI_FAULT_OVERFLOW:
            pfvi_error(r, "pfvi: particle %zu's %s overflowed (not finite) within the step from t = %.17g; "
                    "step not taken, state restored. Lower dt (or u_max).", f->particle,
                    f->flag ? "position" : "velocity", f->t0);
            break;
        case PFVI_FAULT_FORCE:
            pfvi_error(r, "pfvi: the force on particle %zu is not finite at t = %.17g (two particles at one "
                    "position? an additional force returning NaN or Inf?); step not taken, state restored.",
                    f->particle, f->t);
            break;
        case PFVI_FAULT_POLE:
            if (f->n == 2){
                pfvi_error(r, "pfvi: particle %zu: u = omega*dt = %.6g is within %g of a pole of the two-point "
                        "coefficients (cos u = 0 or sin u = 0); step not taken. Lower u_max or dt.",
                        f->particle, f->value, PFVI_POLE_GUARD);
            }else{
                pfvi_error(r, "pfvi: particle %zu: u = omega*dt = %.6g is within %g of a singularity of the "
                        "%zu-stage fitted coefficients; step not taken. Lower u_max or dt.",
                        f->particle, f->value, PFVI_POLE_GUARD, f->n);
            }
            break;
        case PFVI_FAULT_NOT_FINITE:
            pfvi_error(r, "pfvi: particle %zu became non-finite in the step from t = %.17g; step not taken, "
                    "state restored.", f->particle, f->t0);
            break;
        case PFVI_FAULT_KICK:
            pfvi_error(r, "pfvi: the implicit kick for the velocity-dependent force did not converge; step not "
                    "taken, state restored.");
            break;
        case PFVI_FAULT_UNDERFLOW:
            pfvi_error(r, "pfvi: dt = %.3g: dt^2 underflows (|dt| below 1.5e-154), which the %zu-stage equations "
                    "cannot carry; step not taken, state restored. Use stages = 2 or larger time units.", f->h, f->n);
            break;
        case PFVI_FAULT_NOT_CONVERGED:
            if (st->options.epsilon > 0. && f->flag){
                // (A hostile trial: "did not converge (relative change 0)" for a
                // pair closing to 5e-10, whose every trial had converged.)
                pfvi_error(r, "pfvi: the step from t = %.17g was retaken shorter down to t's rounding, its end "
                        "each time closer than it was sized for; not taken, state restored. Colliding? Give the "
                        "bodies radii and set sim.collision (or exit_min_distance).", f->t0);
            }else if (st->options.epsilon > 0.){
                // (The control halved the step down to t's rounding: more
                // steps would not help; forces that are not smooth can leave
                // the stage equations without a solution.)
                pfvi_error(r, "pfvi: the %zu-stage solve did not converge from t = %.17g (%d rounds, change %.3g) "
                        "down to t's rounding; not taken, state restored. A force with a jump or cusp "
                        "there may have no solution: smooth it, or set epsilon = 0.",
                        f->n, f->t0, (int)f->rounds, f->value);
            }else{
                pfvi_error(r, "pfvi: the %zu-stage solve did not converge (relative change %.3g after %d iterations) "
                        "in the step from t = %.17g; step not taken, state restored. Lower dt.",
                        f->n, f->value, (int)f->rounds, f->t0);
            }
            break;
        case PFVI_FAULT_REJECTED:
            pfvi_error(r, "pfvi: no step from t = %.17g meets epsilon = %g (estimate %.3g at dt = %.3g after %d "
                    "tries); step not taken, state restored. Raise epsilon or check the forces.",
                    f->t0, st->options.epsilon, f->value, f->h, PFVI_CONTROL_MAX_REJECTIONS);
            break;
        case PFVI_FAULT_UNSOLVED:
            pfvi_error(r, "pfvi: the reversible step equation from t = %.17g was not solved in %d trial steps "
                    "(last dt = %.6g, estimate/epsilon = %.3g); step not taken, state restored. Try "
                    "step_control = 'seed' or a larger epsilon.", f->t0, (int)f->rounds, f->h, f->value);
            break;
        case PFVI_FAULT_UNSTABLE:
            pfvi_error(r, "pfvi: particle %zu: the %zu-stage step fitted to the fixed omega = %.6g is unstable at "
                    "dt = %.6g against the pull it feels (frequency %.6g): a deviation grows by a factor 1 + %.3g "
                    "per step; not taken, state restored. Use omega near the motion's, a smaller dt, or "
                    "frequency = 'curvature'.", f->particle, f->n, f->value, f->h, f->bound, f->growth);
            break;
        case PFVI_FAULT_CALLBACK_CHANGED:
            pfvi_error(r, "pfvi: a callback replaced additional_forces, gravity_custom or extras during the step "
                    "(force evaluation at t = %.17g); step not taken, state restored. Change them between "
                    "steps (a heartbeat, or between integrate() calls).", f->t);
            break;
        case PFVI_FAULT_VARIATIONS_CHANGED:
            pfvi_error(r, "pfvi: a callback changed the variational particles (N_var from %zu to %zu) during the "
                    "force evaluation at t = %.17g; step not taken, t and the real particles restored. Add "
                    "variations between steps (a heartbeat, or between integrate() calls).", f->n, f->particle, f->t);
            break;
        case PFVI_FAULT_PARTICLE_EDITED:
            if (f->particle == SIZE_MAX){
                pfvi_error(r, "pfvi: a callback changed sim.t during the step (force evaluation at t = %.17g); "
                        "step not taken, t and every particle restored. Change t between steps (a heartbeat, "
                        "or between integrate() calls).", f->t);
            }else if (f->n == 1){
                static const char* const fields[] = PFVI_WRITTEN_FIELDS;
                pfvi_error(r, "pfvi: a callback changed variational particle %zu's %s during the step (force "
                        "evaluation at t = %.17g); step not taken, every particle and t restored. Edit them "
                        "between steps (a heartbeat, or between integrate() calls).", f->particle, fields[f->flag],
                        f->t);
            }else{
                static const char* const fields[] = PFVI_WRITTEN_FIELDS;
                pfvi_error(r, "pfvi: a callback changed particle %zu's %s during the step (force evaluation at "
                        "t = %.17g); step not taken, t and every particle restored (the edit too). Edit "
                        "particles between steps (a heartbeat, or between integrate() calls).",
                        f->particle, fields[f->flag], f->t);
            }
            break;
        case PFVI_FAULT_UNRESOLVED_FIXED:
            pfvi_error(r, "pfvi: the fixed step dt = %.6g from t = %.10g spans %.3g radians of the fastest orbit "
                    "(above " PFVI_STR(PFVI_FIXED_KAPPA_MAX) "): particle %zu%s. Step not "
                    "taken, state restored. Use a shorter dt or epsilon > 0.", f->h, f->t0, f->bound, f->particle,
                    f->flag ? " passes its pericentre inside it" : "'s stages describe no motion");
            break;
        case PFVI_FAULT_VARIATIONAL:
            {
                static const char* const fields[] = PFVI_WRITTEN_FIELDS;
                pfvi_error(r, "pfvi: variational particle %zu (sim.particles_var[%zu], a variation of particle %zu) "
                        "has %s = %s at t = %.17g; step not taken, t and every particle, real and variational, "
                        "unchanged.", f->particle, f->particle, f->n, fields[f->flag],
                        isnan(f->value) ? "NaN" : (f->value > 0.) ? "inf" : "-inf", f->t0);
            }
            break;
        case PFVI_FAULT_REBOUND_ERROR:
            // REBOUND's own message names the cause; a second one would be
            // left behind in its queue, to be raised by the next call.
            break;
        case PFVI_FAULT_NONE:
            pfvi_error(r, "pfvi: step not taken (no cause recorded).");
            break;
    }
}

// Whether value is one of an option's values; if not, says which are.
// (Checked at every step: the message is built only on failure.)
static int pfvi_enum_valid(struct reb_simulation* r, const char* field, int value,
        const struct reb_binarydata_enum_descriptor* values, size_t count){
    if (value >= 0 && (size_t)value < count && values[value].value == value){
        return 1;  // (the X-macro lists give values 0, 1, ... in order)
    }
    for (const struct reb_binarydata_enum_descriptor* d=values; d->name[0]; d++){
        if (d->value == value){
            return 1;
        }
    }
    char allowed[REB_STRING_SIZE_MAX] = "";
    size_t used = 0;
    for (const struct reb_binarydata_enum_descriptor* d=values; d->name[0]; d++){
        const int n = snprintf(allowed + used, sizeof(allowed) - used, "%s'%s'", used ? ", " : "", d->name);
        used = (n > 0 && used + (size_t)n < sizeof(allowed)) ? used + (size_t)n : used;
    }
    pfvi_error(r, "pfvi: integrator.%s = %d is not valid; allowed: %s.", field, value, allowed);
    return 0;
}

#define PFVI_ENUM_VALID(r, field, value, values) \
    pfvi_enum_valid(r, field, value, values, sizeof(values)/sizeof(values[0]) - 1)

static int pfvi_options_valid(struct reb_simulation* r, const struct pfvi_options* o){
    if (!PFVI_ENUM_VALID(r, "fitting", o->fitting, pfvi_fitting_enum)
            || !PFVI_ENUM_VALID(r, "frequency", o->frequency, pfvi_frequency_enum)
            || !PFVI_ENUM_VALID(r, "centre", o->centre, pfvi_centre_enum)){
        return 0;
    }
    if (o->stages < PFVI_STAGES_MIN || o->stages > PFVI_STAGES_MAX){
        pfvi_error(r, "pfvi: integrator.stages = %d is not supported; allowed: %d to %d.",
                o->stages, PFVI_STAGES_MIN, PFVI_STAGES_MAX);
        return 0;
    }
    if (!(isfinite(o->omega) && o->omega >= 0.)){
        // (Checked whatever the frequency: a value set and not yet used is
        // refused now, not when frequency 'fixed' is chosen later.)
        pfvi_error(r, "pfvi: integrator.omega = %g is not valid%s; it must be finite and >= 0.", o->omega,
                (o->frequency == PFVI_FREQUENCY_FIXED) ? " with frequency 'fixed'"
                : " (checked whatever the frequency; frequency 'fixed' reads it)");
        return 0;
    }
    if (!(o->u_max > 0. && o->u_max < M_PI)){
        pfvi_error(r, "pfvi: integrator.u_max = %g is not valid; it must lie in (0, pi).", o->u_max);
        return 0;
    }
    if (!(isfinite(o->epsilon) && o->epsilon >= 0.)){
        pfvi_error(r, "pfvi: integrator.epsilon = %g is not valid; it must be finite and >= 0 (0: fixed steps of sim.dt).", o->epsilon);
        return 0;
    }
    if (!PFVI_ENUM_VALID(r, "step_control", o->step_control, pfvi_step_control_enum)){
        return 0;
    }
    if (!(isfinite(r->dt) && r->dt != 0.)){
        pfvi_error(r, "pfvi: sim.dt = %g is not valid; the time step must be finite and non-zero.", r->dt);
        return 0;
    }
    if (!isfinite(r->G)){
        pfvi_error(r, "pfvi: sim.G = %g is not finite.", r->G);
        return 0;
    }
    if (!isfinite(r->t)){
        pfvi_error(r, "pfvi: sim.t = %g is not finite.", r->t);
        return 0;
    }
    if (!isfinite(r->softening)){
        // (Else every force reads NaN, and the message blamed particle 0.)
        pfvi_error(r, "pfvi: sim.softening = %g is not finite; step not taken.", r->softening);
        return 0;
    }
    if (r->N_active != SIZE_MAX && r->N_active > r->N){
        // REBOUND's gravity loops i < N_active over the particles: past N it
        // reads and writes beyond them.
        pfvi_error(r, "pfvi: sim.N_active = %zu is larger than sim.N = %zu; it must be at most N (or -1: all "
                "active). Step not taken.", r->N_active, r->N);
        return 0;
    }
    if (r->collision != REB_COLLISION_NONE){
        // The contact search inside the step reads radii above 0 as bodies
        // (pfvi_contact.c), REBOUND's own search squares their sum: a radius
        // that is NaN or negative met a contact at any distance in one and at
        // none in the other (a hostile trial). Refused by name instead.
        for (size_t i=0; i<r->N; i++){
            const double radius = r->particles[i].r;
            if (!(isfinite(radius) && radius >= 0.)){
                pfvi_error(r, "pfvi: particle %zu has r = %g; with collisions on, a radius must be finite and >= 0 "
                        "(0: a point). Step not taken.", i, radius);
                return 0;
            }
        }
    }
    if (!(r->exit_min_distance >= 0.) || isinf(r->exit_min_distance)){
        // REBOUND squares it, so a negative one would stop its own check but
        // not pfvi's search inside the step (which reads > 0 as on).
        pfvi_error(r, "pfvi: sim.exit_min_distance = %g is not valid; it must be finite and >= 0 (0: off). "
                "Step not taken.", r->exit_min_distance);
        return 0;
    }
    if (r->gravity != REB_GRAVITY_NONE && r->gravity != REB_GRAVITY_BASIC && r->gravity != REB_GRAVITY_COMPENSATED
            && r->gravity != REB_GRAVITY_TREE && r->gravity != REB_GRAVITY_CUSTOM){
        // 'jacobi' computes WHFast's Jacobi terms (with pfvi: no force at
        // all, free motion); 'mercurius' and 'trace' are those integrators'
        // own (REBOUND raises mid-step, after the step's first stages).
        const char* const name = (r->gravity == REB_GRAVITY_JACOBI) ? "'jacobi'"
            : (r->gravity == 4) ? "'mercurius'" : (r->gravity == 6) ? "'trace'" : "not a mode";
        pfvi_error(r, "pfvi: sim.gravity = %d (%s) is not supported: pfvi needs the forces in the simulation's own "
                "frame, from 'basic' (the default), 'compensated', 'tree', 'none' or a custom routine. Step not "
                "taken.", (int)r->gravity, name);
        return 0;
    }
    if (r->N_var && r->gravity != REB_GRAVITY_BASIC){
        const char* const mode = (r->gravity == REB_GRAVITY_NONE) ? "'none'" : (r->gravity == REB_GRAVITY_COMPENSATED)
            ? "'compensated'" : (r->gravity == REB_GRAVITY_TREE) ? "'tree'" : "custom";
        pfvi_error(r, "pfvi: variational particles (N_var = %zu) need sim.gravity = 'basic', the one mode in "
                "which REBOUND computes their forces; not supported with sim.gravity = %s.", r->N_var, mode);
        return 0;
    }
    if (r->N_var && r->force_is_velocity_dependent){
        pfvi_error(r, "pfvi: variational particles (N_var = %zu) with velocity-dependent forces "
                "(sim.force_is_velocity_dependent = 1) are not supported; first- and second-order variations "
                "under forces of positions alone are.", r->N_var);
        return 0;
    }
    return 1;
}

// The hooks a refused step holds until REBOUND synchronizes at the end of
// the call, and gives back there.
static void hooks_hold(struct reb_simulation* r, struct pfvi_state* st){
    st->hooks_held = 1;
    st->held_pre = r->pre_timestep_modifications;
    st->held_post = r->post_timestep_modifications;
    st->held_heartbeat = r->heartbeat;
    st->held_collision = (int)r->collision;
    r->pre_timestep_modifications = NULL;
    r->post_timestep_modifications = NULL;
    r->heartbeat = NULL;
    r->collision = REB_COLLISION_NONE;
}

static void hooks_release(struct reb_simulation* r, struct pfvi_state* st){
    if (!st->hooks_held){
        return;
    }
    st->hooks_held = 0;
    r->pre_timestep_modifications = st->held_pre;
    r->post_timestep_modifications = st->held_post;
    r->heartbeat = st->held_heartbeat;
    r->collision = st->held_collision;
}

// REBOUND synchronizes at the end of steps() and integrate() and around
// pre- and post-timestep modifications: user code may run next and change
// what the force depends on where no field shows it (a callback's own
// variables, REBOUNDx parameters), so the next step evaluates its start force
// afresh, as a new integrate() would.
static void pfvi_synchronize(struct reb_simulation* r, void* state){
    struct pfvi_state* const st = state;
    if (st){
        st->cache_N = 0;
        st->dt_at_sync = r->dt;
        if (st->in_step == PFVI_STEP_IDLE){
            hooks_release(r, st);
        }
    }
}

static void pfvi_did_add_particle(struct reb_simulation* r){
    if (r->integrator.state){
        pfvi_track_added(r->integrator.state);
    }
}

static void pfvi_will_remove_particle(struct reb_simulation* r, size_t index){
    if (r->integrator.state){
        pfvi_track_removed(r->integrator.state, index);
    }
}

// The checks a step needs before it changes anything, then the start force
// (reused from the last step where nothing it depends on can have changed)
// and the frequencies. Returns 0, with the error reported, if no step can start.
// keep_end: an output step from the run's end (glue_start's show inside):
// the run's end force is left as its step left it (with velocity-dependent
// forces the end stage's, at the stage velocity, not the force at the end
// velocity), so that the run's next step finds what a single call's does.
static int pfvi_step_start(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, int keep_end){
    struct reb_particle* const ps = r->particles;
    struct pfvi_end_state* const e = st->end;
    // e[i].a becomes the acceleration at the start of this step. It is kept
    // from the last step unless anything may have changed the forces: a new
    // integrate() or steps() call (REBOUND resets dt_last_done to 0, or
    // synchronizes at the end of the last), a heartbeat (it may change
    // anything), velocity-dependent forces, ODEs beside a force callback
    // (REBOUND steps them after the step; a force that reads their state
    // reads it anew: one kept saw the last step's, and a no-op heartbeat
    // moved a run by 1e-4, a hostile trial), or any bit of N, t, the force
    // model (struct pfvi_force_model), a position, velocity or mass.
    // (Timestep hooks: REBOUND synchronizes before them, which drops the end.)
    const int reuse = (r->dt_last_done != 0. || st->output_taken_up) && !r->force_is_velocity_dependent && !r->heartbeat
        && !(r->N_odes && pfvi_forces_run_user_code(r)) && pfvi_end_is_start(r, st);
    if (!reuse){
        // Checked before anything is changed, so that a refusal leaves the
        // integrator's own state as it was too.
        for (size_t i=0; i<N; i++){
            if (!pfvi_particle_finite(&ps[i])){
                // (the first field at fault, by name)
                const struct reb_particle* const q = &ps[i];
                const char* const names[7] = {"x", "y", "z", "vx", "vy", "vz", "m"};
                const double values[7] = {q->x, q->y, q->z, q->vx, q->vy, q->vz, q->m};
                int k = 0;
                while (k < 6 && isfinite(values[k])){
                    k++;
                }
                pfvi_error(r, "pfvi: particle %zu has %s = %g, not finite; step not taken.", i, names[k], values[k]);
                return 0;
            }
            if (ps[i].m < 0.){
                pfvi_error(r, "pfvi: particle %zu has a negative mass m = %.17g; masses must be >= 0. Step not taken.", i, ps[i].m);
                return 0;
            }
        }
        pfvi_forget_edited(r, st);
        pfvi_discard_implausible(r, st);
    }
    // The density the last step found at its end holds here if the state,
    // the force model and the accelerations are that end's, bit for bit.
    int density_holds = st->density_N == N && st->density_stages == st->options.stages && pfvi_state_is_end(r, st);
    // The variational particles' start forces are reused with the real ones,
    // if they too are as the last step left them (REBOUND rescales them
    // between steps once they grow past 1e100); edited, their stages no
    // longer predict this step's.
    const int var_reuse = st->var_N && pfvi_var_is_end(r, st);
    if (st->var_N && st->var_end_N == st->var_N && !var_reuse){
        st->var_predictor_N = 0;
    }
    st->cache_N = 0;
    memcpy(st->start, ps, N*sizeof(struct reb_particle));
    if (st->var_N){
        memcpy(st->var_start, r->particles_var, st->var_N*sizeof(struct reb_particle));
    }
    if (!reuse){
        if (!pfvi_update_acceleration(r, st, N, t0)){
            pfvi_report(r, st);
            return 0;
        }
        for (size_t i=0; !keep_end && i<N; i++){
            density_holds &= (e[i].a[0] == ps[i].ax) & (e[i].a[1] == ps[i].ay) & (e[i].a[2] == ps[i].az);
            e[i].a[0] = ps[i].ax; e[i].a[1] = ps[i].ay; e[i].a[2] = ps[i].az;
        }
    }else if (st->var_N && !var_reuse){
        // Their forces alone are new (the real ones, recomputed at the same
        // positions, are kept from the last step as they are without them).
        if (!pfvi_update_acceleration(r, st, N, t0)){
            pfvi_report(r, st);
            return 0;
        }
        st->statistics.n_variational_evaluations++;
    }
    if (st->var_N && !(reuse && var_reuse)){
        pfvi_var_keep_end(r, st);  // var_end: the start state and its forces
    }
    const struct reb_particle* const p0 = st->start;
    const struct pfvi_options* const o = &st->options;
    const int fitted = (o->fitting != PFVI_FITTING_NONE);
    const int symmetric = (o->epsilon > 0. && o->step_control == PFVI_STEP_CONTROL_SYMMETRIC);
    // (The s-point stage solve's Newton rounds correct each body with its partner's pull.)
    const int need_partner = (fitted && (o->centre == PFVI_CENTRE_PARTNER || o->frequency == PFVI_FREQUENCY_MEAN_MOTION))
        || o->stages > 2;
    // The partners (and for the symmetric control the density) at the start:
    // those the last step found at its end if this step starts there.
    st->density_N = 0;  // valid again only once a symmetric step has found it at its end
    if (!density_holds){
        st->density_sigma = 0.;
        st->density_dlog = 0.;
        if (symmetric || need_partner){
            struct pfvi_field field;
            if (!pfvi_field_of(r, st, &field)){
                pfvi_report(r, st);
                return 0;
            }
            if (symmetric){
                pfvi_step_density(p0, e, N, &field, o->stages, st->partners,
                        &st->density_sigma, &st->density_dlog, NULL);
            }else{
                pfvi_partner_search(p0, N, &field, st->partners);
            }
        }
    }
    const int centre_partner = (fitted && (o->centre == PFVI_CENTRE_PARTNER || o->frequency == PFVI_FREQUENCY_MEAN_MOTION));
    pfvi_centres(p0, e, N, r->N_active, (r->gravity == REB_GRAVITY_NONE) ? 0. : r->G,
            fitted ? o->centre : PFVI_CENTRE_ORIGIN, centre_partner ? st->partners : NULL, st->centre);
    for (size_t i=0; !fitted && i<N; i++){
        st->omega_fit[i] = 0.;
    }
    for (size_t i=0; fitted && i<N; i++){
        const size_t j = st->centre[i].partner;
        st->omega_fit[i] = pfvi_frequency(o, &p0[i], (j == SIZE_MAX) ? NULL : &p0[j], &st->centre[i], e[i].a);
        if (isnan(st->omega_fit[i])){
            pfvi_roll_back(r, st, N, t0);
            pfvi_error(r, "pfvi: particle %zu: its %s frequency is not a number at t = %.17g; "
                    "step not taken, state restored.", i, pfvi_frequency_enum[o->frequency].name, t0);
            return 0;
        }
    }
    return 1;
}

// One step of fixed length sim.dt; returns it, or 0 if refused.
static double pfvi_fixed_step(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0){
    const double h = r->dt;
    const enum pfvi_trial trial = pfvi_trial_step(r, st, N, t0, h);
    if (trial == PFVI_TRIAL_NOT_CONVERGED){
        pfvi_give_up(st, (struct pfvi_fault){.kind = PFVI_FAULT_NOT_CONVERGED, .n = (size_t)st->options.stages,
            .value = st->trial.change, .rounds = st->trial.rounds, .t0 = t0});
    }
    if (trial != PFVI_TRIAL_OK){
        return 0.;
    }
    struct pfvi_fixed_check check;
    if (!pfvi_fixed_step_check(r, st, N, t0, h, &check)){
        return 0.;
    }
    // (The kappa at which the symmetric control's steps err by FIXED_WARN per orbit.)
    static const double constant[PFVI_STAGES_MAX + 1] = PFVI_SYMMETRIC_CONSTANTS;
    const int s = st->options.stages;
    const double kappa_warn = pow(PFVI_FIXED_WARN/constant[s], 1./(2.*s - 2.));
    const int by_density = check.saturated && check.kappa > kappa_warn;
    const int unpaired = check.saturated && !(check.kappa > 0.);
    if ((check.error > PFVI_FIXED_WARN || by_density || unpaired) && !st->fixed_warned){
        st->fixed_warned = 1;
        // The stages' estimate saturates (pfvi_fixed_step_check): a lower
        // bound, said so, with the span the density measured.
        if (check.error > PFVI_FIXED_WARN){
            pfvi_warning(r, "pfvi: the fixed step dt = %.6g from t = %.10g spans %.2g radians of the "
                    "fastest orbit; particle %zu's stages imply a position error of at least %.2g per orbit (above "
                    PFVI_STR(PFVI_FIXED_WARN) "). Use a shorter dt or epsilon > 0. Said once per simulation.",
                    h, t0, check.kappa, check.particle, check.error);
        }else if (by_density){
            pfvi_warning(r, "pfvi: the fixed step dt = %.6g from t = %.10g spans %.2g radians of the "
                    "fastest orbit, where steps err by more than " PFVI_STR(PFVI_FIXED_WARN) " per orbit (above "
                    "%.2g). Use a shorter dt or epsilon > 0. Said once per simulation.", h, t0, check.kappa, kappa_warn);
        }else{
            pfvi_warning(r, "pfvi: the fixed step dt = %.6g from t = %.10g is not resolved: particle %zu's "
                    "forces turn by %.2g radians in it, where its stages' estimate saturates, and no pair sets a "
                    "time scale. Use a shorter dt or epsilon > 0. Said once per simulation.", h, t0, check.particle,
                    check.u);
        }
    }
    pfvi_commit_step(r, st, N, h);
    return h;
}

// One step: fixed (epsilon 0) or by the step control.
static double pfvi_take(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0){
    return (st->options.epsilon == 0.) ? pfvi_fixed_step(r, st, N, t0) : pfvi_controlled_step(r, st, N, t0);
}

// The pair of largest G (m_i + m_j)/r^3 (their time scale's inverse omega
// and separation r), for the message of a step that stopped changing t. O(N^2),
// on that refusal only. Returns 0 without an attracting pair.
static int pfvi_tightest_pair(const struct reb_simulation* r, size_t N, size_t* i_out, size_t* j_out,
        double* separation, double* omega){
    const struct reb_particle* const p = r->particles;
    const size_t n_active = (r->N_active < N) ? r->N_active : N;
    double best = 0.;
    for (size_t i=0; i<N; i++){
        for (size_t j=0; j<i && j<n_active; j++){
            const double m = p[i].m + p[j].m;
            const double dx = p[i].x - p[j].x, dy = p[i].y - p[j].y, dz = p[i].z - p[j].z;
            const double r2 = dx*dx + dy*dy + dz*dz + r->softening*r->softening;
            const double w2 = r->G*m/(r2*sqrt(r2));
            if (w2 > best && isfinite(w2)){
                best = w2;
                *i_out = j;
                *j_out = i;
                *separation = sqrt(r2);
            }
        }
    }
    *omega = sqrt(best);
    return best > 0.;
}

/* ------------------------------------------------------------- the step glue
 *
 * One call of pfvi's step is a walk through these states (docs/outputs.md):
 *
 *   entry --(an output is shown, unedited)--> TAKE_UP --(the run's state is
 *     what REBOUND should see next: a step on, or a contact not yet shown)--> done
 *                                                |
 *   entry --(otherwise)------------------------> START (the step's start: checks,
 *     force, density; refused --> done)
 *       START --(finishing on a time inside the run's last step)--> SHOW_INSIDE
 *                 (an output step from its end; done, or cut --> STEP)
 *       START --(otherwise)--> STEP (a step of the run: its whole interval where
 *                 an output will show the time, cut at sim.dt where REBOUND's own
 *                 outputs are needed; refused --> done)
 *       STEP --(finishing, and the step passed the time)--> SHOW_PASSED --> done
 *
 * "Finishing" is REBOUND's LAST_STEP (sim.dt cut to reach a requested time);
 * outputs are shown only where pfvi_output_eligible (the symmetric control,
 * epsilon > 0, fitting 'none', no hook that needs REBOUND's own outputs).
 */
enum pfvi_glue {
    PFVI_GLUE_TAKE_UP,
    PFVI_GLUE_START,
    PFVI_GLUE_SHOW_INSIDE,
    PFVI_GLUE_STEP,
    PFVI_GLUE_SHOW_PASSED,
    PFVI_GLUE_DONE,
};

// What the call found at its entry, and what its states pass on.
struct pfvi_call {
    double t_entry, dt_entry, t_target;
    double proposed;        // the time REBOUND may see next (the run's proposal)
    int finishing;          // REBOUND's LAST_STEP: sim.dt cut to reach t_target (or a request passed)
    int bounded;            // integrate()'s requested time lies ahead: no state past it is shown
    double request;         // that time
    int eligible;           // outputs may be shown (pfvi_output_eligible)
    int shown;              // an output is shown, unedited
    int at_end;             // the simulation is at the run's last step's end
    int dense;              // this step takes its whole interval; an output shows t_target
    double t0;              // where the step starts (after a take-up: the run's state)
    size_t density_N;       // the density the last step found at its end
    double density_sigma, density_dlog;
    uint64_t contact_steps; // n_contact_steps before the step
    double h;               // the step taken
    double user_cap;        // a user's sim.dt REBOUND cut to finish (user_cap_cut): it caps the step
    double entry_cap;       // from an edited output, REBOUND's cut to finish: the run's proposal caps instead
    int unwrapped;          // the run's end, which REBOUND's periodic wrap had moved, put back
};

// The dt_last_done a call that shows an output reports. On a finishing step
// (REBOUND's last of the call), the time the state shown has lived since the
// state REBOUND held before the step, as after a step cut to the time, so that
// a heartbeat gets the time passed (before, the run's proposal: 50 outputs
// over 20 time units summed to 48.5). Elsewhere (a step taking the run up from
// an output), the run's proposal: REBOUND restores sim.dt after integrate()
// from the dt_last_done of the step before its finishing one, and decides the
// next call's finish from that; the time lived there (measured) left it
// below the proposal, and every later call showed its time in two output
// steps (Kepler at 100 outputs a period: 19652 against 10000). 0 with
// 'line'/'linetree' collisions and radii, so that REBOUND's search looks at
// the state shown, not along a segment drawn back from it over a step it did
// not take (the run's steps are searched along their paths). (A lived time of
// 0 would read as a call's start: the proposal then.)
static double pfvi_shown_dt_done(const struct reb_simulation* r, const struct pfvi_call* c, double proposed){
    const double lived = r->t - c->t_entry;
    return (pfvi_contact_line(r) && pfvi_contact_enabled(r)) ? 0. : ((c->finishing && lived != 0.) ? lived : proposed);
}

// A refused call leaves the simulation as it found it: a shown output shown.
static void glue_show_again(struct reb_simulation* r, struct pfvi_state* st, const struct pfvi_call* c){
    if (c->shown){
        pfvi_output_show_again(r, st);
        r->dt = c->dt_entry;
    }else if (c->unwrapped){
        pfvi_output_boundary(r);   // (the state was REBOUND's wrap of the end: the same again)
    }
}

// How far a requested time may lie from the run's state at t and still be
// that state's time (PFVI_OUTPUT_NEAR): 1e-12 of the time the run has spanned
// (its track, or the last step where the track is not kept) and a few of t's
// last places, for the rounding a round trip's steps leave in t.
static double output_near(const struct pfvi_state* st, double t, double step){
    const double span = fmax(fabs(step), st->track_seen_hi - st->track_seen_lo);
    return PFVI_OUTPUT_NEAR*span + PFVI_OUTPUT_NEAR_ULPS*DBL_EPSILON*fabs(t);
}

// Whether sim.dt is a value REBOUND restores after integrate() from one of
// pfvi's own (pfvi_step), not one the user set; at_end: the simulation is
// still the run's last step's end, unedited.
static int rebound_restored_value(const struct pfvi_state* st, double dt, int at_end){
    if (dt == st->dt_user){
        return 0;
    }
    return (st->dt_rebound_leaves != 0. && dt == fabs(st->dt_rebound_leaves))
        || (st->dt_call_began != 0. && dt == fabs(st->dt_call_began)
            && (!st->dt_call_default || ((at_end || st->dt_call_first_cut) && st->call_is_integrate)))
        || (st->dt_call_cut != 0. && dt == fabs(st->dt_call_cut));
}

static int rebound_restored(const struct reb_simulation* r, const struct pfvi_state* st, int at_end){
    return rebound_restored_value(st, fabs(r->dt), at_end);
}

static int rebound_restore_known(const struct pfvi_state* st){
    return st->dt_rebound_leaves != 0. || (st->dt_call_began != 0. && !st->dt_call_default) || st->dt_call_cut != 0.;
}

static int rebound_restored_at_end(const struct reb_simulation* r, const struct pfvi_state* st){
    return rebound_restored(r, st, 1) && pfvi_state_is_end(r, st);
}

// A sim.dt the user set since the last call: one REBOUND could not have
// restored. (Not on a finishing step, whose sim.dt REBOUND cut; nor on the
// first call of a simulation loaded from a snapshot REBOUND wrote during a
// call, whose sim.dt is REBOUND's working value there.)
static int user_set_dt(const struct reb_simulation* r, const struct pfvi_state* st, const struct pfvi_call* c){
    return !c->finishing && (st->end_N != 0 || st->snapshot_between_calls) && rebound_restore_known(st)
        && !rebound_restored(r, st, 0);
}

// The same on an integrate() whose first step REBOUND cut to finish on its
// time (the user's sim.dt at least the time to it): the value the call
// began with (dt_call_entry), which caps the step from the output as it
// would in a call to a later time; 0 if it is not the user's.
static double user_cap_cut(const struct pfvi_state* st, const struct pfvi_call* c){
    const double entry = fabs(st->dt_call_entry);
    const int user = c->finishing && st->call_is_integrate && st->request_set && entry != 0.
        && entry != fabs(st->dt_proposed)
        && (st->end_N != 0 || st->snapshot_between_calls || st->request_entry_cut != 0.)
        && rebound_restore_known(st) && !rebound_restored_value(st, entry, 0);
    return user ? entry : 0.;
}

// A call that would pass integrate()'s requested time finishes on it.
// passed: the dt_last_done the state past it would have been shown with,
// which REBOUND's finish on the time would then have kept as its last full
// step and left as sim.dt (pfvi_request_end leaves it; 0: REBOUND's restore
// of the dt the call began with stands, as it would).
static void request_finish(struct pfvi_state* st, struct pfvi_call* c, double passed){
    c->finishing = 1;
    c->t_target = c->request;
    st->request_shown = 1;
    st->request_dt_leaves = passed;
}

static enum pfvi_glue glue_entry(struct reb_simulation* r, struct pfvi_state* st, struct pfvi_call* c){
    *c = (struct pfvi_call){.t_entry = r->t, .dt_entry = r->dt, .t_target = r->t + r->dt};
    c->finishing = (st->status_at_start == REB_STATUS_LAST_STEP);
    c->eligible = pfvi_output_eligible(r, st);
    // A sim.dt set by the user since the output (not the one REBOUND left)
    // is honoured as after any edit, as IAS15 would: the shown state becomes
    // the user's and the step from it is capped by that dt.
    // (REBOUND flips its sign for a run backwards: a reversal, not a new dt.)
    // (Asked only where an output is held: mid-run, nothing is.)
    // (Also where the simulation holds the run's own step end, no output:
    // else the cap waited for the next call, whose sim.dt REBOUND restored
    // to it: a hostile trial, 14 steps against 12.)
    c->user_cap = c->eligible ? user_cap_cut(st, c) : 0.;
    c->shown = c->eligible && st->output_N != 0 && !user_set_dt(r, st, c) && c->user_cap == 0.
        && pfvi_output_is_shown(r, st);
    if (c->user_cap != 0. && st->dt_user != c->user_cap){
        st->dt_user = c->user_cap;
        st->dt_user_spent = 0;
    }
    // The run's last step's end as REBOUND's periodic wrap left it: the end
    // itself again, so that a time inside that step is shown from there as
    // without the wrap; the wrap is made again where the run goes on
    // (glue_start).
    c->unwrapped = !c->shown && c->eligible && pfvi_output_unwrap(r, st);
    // Forces pfvi cannot see into may have changed since (a callback's own
    // variables, a REBOUNDx force added, removed or given a new parameter):
    // the run's step past the output was made with the old ones. Changed,
    // the output is taken as edited, and the run goes on from it.
    const int hold = c->shown ? pfvi_output_forces_hold(r, st) : 1;
    if (hold < 0){
        pfvi_report(r, st);
        return PFVI_GLUE_DONE;   // (the output still shown, as it was)
    }
    c->shown = c->shown && hold;
    const int output_held = st->output_N != 0 || st->output_resized;
    st->output_resized = 0;
    if (c->user_cap == 0. && !c->shown && !c->unwrapped && c->eligible && output_held && st->dt_proposed != 0.
            && st->call_is_integrate && st->request_set && !user_set_dt(r, st, c)){
        // An output held and taken as edited (an option, a particle or a
        // force changed, a particle added or removed since): the step from
        // it starts from the run's own
        // proposal, not from the sim.dt REBOUND restored after the last call
        // (its last full step, which depends on the output times), nor from
        // REBOUND's cut to finish on the next one, so that outputs leave the
        // edited run as they leave any other (a hostile trial: epsilon set at
        // an output, 7 steps to t = 4.6 in one call and 6 with one more
        // output; 124 of 200 runs with such edits off).
        if (c->finishing){
            c->entry_cap = fabs(st->dt_proposed);
        }else if (rebound_restored(r, st, 0)){
            r->dt = copysign(st->dt_proposed, r->dt);
        }
    }
    // (Compared only where an output may be shown from the last step's end.
    // A simulation loaded from an archive or copied keeps no end state: it
    // is at the last step's end if t is where that step ended, as REBOUND
    // snapshots it between that step and the call that shows the output.)
    const int loaded_end = c->eligible && c->finishing && st->end_N == 0
        && st->output_last_t1 != st->output_last_t0 && r->t == st->output_last_t1;
    c->at_end = c->shown || (c->eligible && c->finishing && (loaded_end || pfvi_state_is_end(r, st)));
    if (c->eligible && !c->finishing && !c->shown && st->dt_proposed != 0. && r->dt != 0.
            && st->output_last_t1 != st->output_last_t0 && r->t == st->output_last_t1
            && fabs(r->dt) != fabs(st->dt_proposed)
            && ((st->end_N == 0) ? (!st->snapshot_between_calls || rebound_restored(r, st, 1))
                : rebound_restored_at_end(r, st))){
        // Such a snapshot holds as sim.dt the cut REBOUND made to finish on
        // the next output (it writes it after deciding to finish, before the
        // call that does); the run would have gone on with its proposal.
        // So does a call whose step ended exactly on its time: REBOUND cut
        // nothing and restored its last full step or the dt the call began
        // with, which would cap the next step (issue 42: 23 of 40 step ends).
        // (A snapshot written between calls holds sim.dt as the run left it:
        // judged as the run judges it.)
        r->dt = copysign(st->dt_proposed, r->dt);
    }
    // (A value of REBOUND's own would cap the next step.)
    c->proposed = (st->dt_proposed != 0.) ? st->dt_proposed : c->dt_entry;
    // REBOUND decided this step does not finish because t + sim.dt falls
    // short of the requested time; pfvi's step may be longer than sim.dt (a
    // new simulation's first), and the run's end taken up after an output
    // may lie past it. Neither is shown: REBOUND's collision
    // search, Encounter, Escape, heartbeat and archive would see a time the
    // call never reaches (a hostile trial: Encounter raised at t = 0.077 by
    // integrate(0.01)). The time is shown as a finishing step shows it.
    c->bounded = !c->finishing && c->eligible && st->request_set && r->exact_finish_time == 1
        && (st->request_t - r->t)*r->dt > 0.;
    c->request = st->request_t;
    if (c->finishing && c->eligible && st->request_set && r->exact_finish_time == 1 && c->t_target != c->request
            && fabs(c->t_target - c->request) <= PFVI_OUTPUT_NEAR_ULPS*DBL_EPSILON*fmax(fabs(c->request), fabs(r->t))){
        // REBOUND's cut, t + (t_request - t), rounds a place or two from the
        // time asked for (a hook saw t a place past it): shown on the time itself.
        c->t_target = c->request;
    }
    if (c->bounded && c->shown && (st->output_t_real - c->request)*r->dt > 0.){
        // (the take-up's: pfvi_shown_dt_done of a step on)
        request_finish(st, c, (pfvi_contact_line(r) && pfvi_contact_enabled(r)) ? 0. : c->proposed);
    }
    if (c->shown){
        return PFVI_GLUE_TAKE_UP;
    }
    st->output_N = 0;  // what the simulation holds is the run's state, or the user's
    return PFVI_GLUE_START;
}

static enum pfvi_glue glue_take_up(struct reb_simulation* r, struct pfvi_state* st, struct pfvi_call* c){
    pfvi_output_take_up(r, st);
    r->dt = c->finishing ? c->t_target - r->t : c->dt_entry;
    const int contact_first = st->output_contact_pending && (c->t_target - r->t)*c->dt_entry > 0.;
    if ((!c->finishing && (r->t - c->t_entry)*c->dt_entry >= 0.) || contact_first){
        // A step on from the output: the run's state lies that way, and
        // going there is the step (REBOUND does not know where the next
        // output is: a time it passed is shown from there). A contact the
        // run's step ended at before the requested time is shown first, so
        // that REBOUND's collision search and Encounter see it (REBOUND then
        // asks again for the time).
        r->dt = c->proposed;
        r->dt_last_done = pfvi_shown_dt_done(r, c, c->proposed);
        st->output_N = 0;
        st->output_contact_pending = 0;
        return PFVI_GLUE_DONE;
    }
    return PFVI_GLUE_START;
}

static enum pfvi_glue glue_start(struct reb_simulation* r, struct pfvi_state* st, struct pfvi_call* c, size_t N){
    const double t0 = c->t0 = r->t;
    // (A contact search (pfvi_contact.c) searches the run's own steps: a
    // step retaken to end at a contact past the output shows the output from
    // there, and REBOUND's collision search and Encounter see the contact
    // when an output reaches it.)
    c->dense = c->eligible && (c->finishing || c->shown) && st->options.epsilon > 0.;
    // The last step went from output_last_t0 to t0 (its end unedited): a
    // time inside it is shown from here, with no step of the run.
    const double d = t0 - st->output_last_t0;
    const int near = c->at_end && fabs(c->t_target - t0) <= output_near(st, t0, d);
    const int inside = c->dense && c->finishing && (near || (c->at_end && t0 == st->output_last_t1
        && (t0 - c->t_target)*d > 0. && (c->t_target - st->output_last_t0)*d > 0.));
    const int show_inside = c->dense && c->finishing && (c->t_target == t0 || (inside && st->output_failed_t != t0));
    if ((c->shown || c->unwrapped) && !show_inside){
        // The run goes on from its own end, taken up or put back: REBOUND's
        // periodic wrap of it first, as a single call had it after the run's
        // step.
        pfvi_output_boundary(r);
    }
    c->density_N = st->density_N;
    c->density_sigma = st->density_sigma;
    c->density_dlog = st->density_dlog;
    const int started = pfvi_step_start(r, st, N, t0, show_inside);
    st->output_taken_up = 0;
    if (!started){
        glue_show_again(r, st, c);
        return PFVI_GLUE_DONE;
    }
    if (show_inside){
        return PFVI_GLUE_SHOW_INSIDE;
    }
    if (inside){
        c->dense = 0;  // an output step from here did not converge: a step of the run cut short
    }
    return PFVI_GLUE_STEP;
}

static enum pfvi_glue glue_show_inside(struct reb_simulation* r, struct pfvi_state* st, struct pfvi_call* c,
        size_t N){
    const double t0 = c->t0;
    const double d = t0 - st->output_last_t0;
    const int near = fabs(c->t_target - t0) <= output_near(st, t0, d);
    const enum pfvi_trial trial = (c->t_target == t0) ? PFVI_TRIAL_OK
        : pfvi_output_present(r, st, N, c->t_target, near);
    if (trial == PFVI_TRIAL_OK){
        // The density found at this state's end still holds for the next step.
        if (c->density_N == N){
            st->density_N = c->density_N;
            st->density_sigma = c->density_sigma;
            st->density_dlog = c->density_dlog;
        }
        r->dt = c->proposed;
        r->dt_last_done = pfvi_shown_dt_done(r, c, c->proposed);
        return PFVI_GLUE_DONE;
    }
    if (trial == PFVI_TRIAL_ERROR){
        // Refused: the simulation as the call found it.
        glue_show_again(r, st, c);
        if (!c->shown){
            st->output_N = 0;
        }
        pfvi_report(r, st);
        return PFVI_GLUE_DONE;
    }
    // Not converged: the time is reached by a step of the run cut short, as
    // before outputs were shown (output_failed_t).
    st->output_failed_t = t0;
    c->dense = 0;
    return PFVI_GLUE_STEP;
}

static enum pfvi_glue glue_step(struct reb_simulation* r, struct pfvi_state* st, struct pfvi_call* c, size_t N){
    const double t0 = c->t0;
    // With collisions and radii, or exit_min_distance: retaken to end at the
    // first contact its path shows (pfvi_contact.c).
    const double uncut = (c->user_cap != 0.) ? c->user_cap : c->entry_cap;
    st->output_uncapped = c->dense && uncut == 0.;
    if (uncut != 0.){
        // The user's value caps the step from the output (a step past the
        // time shows it, as any output step), as a call to a later time
        // takes it; from an edited output, the run's proposal does.
        r->dt = copysign(uncut, r->dt);
    }
    // (sim.dt as the run proposed it is no cut of REBOUND's: capping there
    // would leave slivers of the track's interval where the force model
    // changes between steps, as an ODE's state does.)
    st->output_cut = r->exact_finish_time == 1 && !pfvi_output_hooks_kept(r) && fabs(r->dt) != fabs(st->dt_proposed);
    c->contact_steps = st->statistics.n_contact_steps;
    const double h = c->h = pfvi_contact_enabled(r) ? pfvi_contact_step(r, st, N, t0, pfvi_take)
        : pfvi_take(r, st, N, t0);
    st->output_uncapped = 0;
    st->output_cut = 0;
    if (h == 0.){
        pfvi_report(r, st);
        if (r->t == t0){
            glue_show_again(r, st, c);
            r->dt = (uncut != 0.) ? c->dt_entry : r->dt;
        }
        return PFVI_GLUE_DONE;
    }
    if (r->t == t0){
        // t + h rounds to t: REBOUND would call this step for ever.
        pfvi_roll_back(r, st, N, t0);
        size_t pi = 0, pj = 0;   // (set where the pair is found, the only case read)
        double separation = 0., omega = 0.;
        if (st->options.epsilon > 0. && pfvi_tightest_pair(r, N, &pi, &pj, &separation, &omega)
                && omega*fabs(t0)*DBL_EPSILON > PFVI_TIGHT_PAIR_ROUNDING){
            // The adaptive step followed the tightest pair: not dt's fault.
            // Either it is closing in, or t is too large for its orbit (an e =
            // 0.9 pericentre at t = 1e15, where t's last place is 0.125).
            pfvi_error(r, "pfvi: particles %zu and %zu, %.3g apart at t = %.17g: their time scale %.2g is below t's "
                    "last place %.2g. Not taken, state restored. Colliding: give them radii and set sim.collision "
                    "(or sim.exit_min_distance); else start t nearer 0.", pi, pj, separation, t0, 1./omega,
                    nextafter(fabs(t0), INFINITY) - fabs(t0));
            return PFVI_GLUE_DONE;
        }
        if (st->stage_fault.kind != PFVI_FAULT_NONE){
            // Halved down to t's rounding from a force that was not finite
            // ahead: that force is the cause (a hostile trial: NaN beyond
            // x = -1.2 read "the step dt = 1.16e-16 does not change t").
            st->fault = st->stage_fault;
            pfvi_report(r, st);
            return PFVI_GLUE_DONE;
        }
        pfvi_error(r, "pfvi: the step dt = %.3g does not change t = %.17g (it is below the rounding of t); "
                "step not taken, state restored. Use a larger dt, or start t nearer 0.", h, t0);
        return PFVI_GLUE_DONE;
    }
    // (A finishing step taken up from a shown output that ends short of the
    // time: lived from the output, as pfvi_shown_dt_done; a line search
    // keeps the step it can draw back.)
    r->dt_last_done = (c->shown && c->finishing && !(pfvi_contact_line(r) && pfvi_contact_enabled(r)))
        ? r->t - c->t_entry : h;
    st->dt_user_spent = st->dt_user_spent || c->user_cap != 0.;   // (REBOUND restores it after the call)
    struct pfvi_statistics* const stats = &st->statistics;
    stats->n_steps++;
    stats->iterations_mean = (double)stats->n_iterations/(double)stats->n_steps;
    pfvi_keep_end(r, st, N);  // the end of this step is the start of the next
    if (st->var_N){
        pfvi_var_keep_end(r, st);
        if (r->calculate_megno){
            // MEGNO's sums through REBOUND's own update, as IAS15 and WHFast do,
            // with the step's increment of 2 int (t - t_0) delta.delta'/|delta|^2 dt.
            // REBOUND's <Y> adds Y at the step's end times the step (a
            // rectangle rule, coarse at pfvi's long steps): the sum is given
            // the step's quadrature of Y over its stages instead.
            const double Y_end = megno_Y(r->megno_Ys + st->trial.megno_dY, r->t - r->megno_initial_t);
            r->megno_Yss += st->trial.megno_Y_integral - Y_end*h;
            if (r->t == r->megno_initial_t){
                // REBOUND's update divides by the time since MEGNO began: at
                // that time itself (a way back landing on it exactly, as
                // symmetric steps do) its running Y is 0/0, and every value
                // after it NaN (IAS15 passes the instant by). The sum goes
                // on; the averages skip the instant.
                r->megno_Ys += st->trial.megno_dY;
            }else{
                reb_tools_megno_update(r, st->trial.megno_dY, h);
            }
        }
    }
    st->output_last_t0 = t0;
    st->output_last_t1 = r->t;
    st->output_N = 0;  // the simulation holds the run's state
    st->output_contact_pending = 0;
    if (c->bounded && !c->finishing && (r->t - c->request)*h > 0.){
        request_finish(st, c, r->dt_last_done);   // (the run's step as REBOUND's own decision had it)
        return PFVI_GLUE_SHOW_PASSED;
    }
    return (c->dense && c->finishing && (r->t - c->t_target)*h > 0.) ? PFVI_GLUE_SHOW_PASSED : PFVI_GLUE_DONE;
}

// The step passed the requested time: show the state there.
static enum pfvi_glue glue_show_passed(struct reb_simulation* r, struct pfvi_state* st, struct pfvi_call* c,
        size_t N){
    const double t_end = r->t, h = c->h;
    if (pfvi_output_removed(r)){
        // The bodies an open box lost by the step's end are gone from the
        // run's state, as after a single call's step: the output is drawn
        // from what is left, which starts afresh (as the next step would).
        N = r->N;
        if (N == 0){
            return PFVI_GLUE_DONE;
        }
        if (!pfvi_scratch(st, N)){
            pfvi_report(r, st);
            return PFVI_GLUE_DONE;
        }
        if (!pfvi_step_start(r, st, N, t_end, 0)){
            return PFVI_GLUE_DONE;   // (reported)
        }
        st->output_taken_up = 0;
    }
    const double proposed = r->dt;
    const enum pfvi_trial trial = pfvi_output_present(r, st, N, c->t_target,
            fabs(c->t_target - t_end) <= output_near(st, t_end, h));
    r->dt = proposed;
    if (trial == PFVI_TRIAL_OK){
        r->dt_last_done = pfvi_shown_dt_done(r, c, h);
        st->output_contact_pending = (st->statistics.n_contact_steps != c->contact_steps);
        return PFVI_GLUE_DONE;
    }
    st->output_N = 0;  // the run's state, at the step's end, is the simulation's
    if (trial == PFVI_TRIAL_ERROR){
        pfvi_report(r, st);
    }else{
        st->output_failed_t = t_end;  // REBOUND comes back for the time: a step cut short
    }
    return PFVI_GLUE_DONE;
}


static void pfvi_step_take(struct reb_simulation* r, struct pfvi_state* st){
    if (!pfvi_options_valid(r, &st->settings)){
        return;
    }
    st->options = st->settings;  // what this step runs with, whatever a callback sets during it
    const size_t N = r->N;
    if (N == 0){
        const double t0 = r->t;
        if (t0 + r->dt == t0){
            pfvi_error(r, "pfvi: the step dt = %.3g does not change t = %.17g (it is below the rounding of t); "
                    "step not taken.", r->dt, t0);
            return;
        }
        r->t = t0 + r->dt;
        r->dt_last_done = r->dt;
        st->statistics.n_steps++;
        return;
    }
    st->fault.kind = PFVI_FAULT_NONE;  // a refusing layer writes the whole record
    st->stage_fault.kind = PFVI_FAULT_NONE;
    st->retry_valid = 0;  // a step starts from the last step's stages, never from a refused one's
    if (!pfvi_scratch(st, N)){
        pfvi_report(r, st);
        return;
    }
    st->var_N = r->N_var;
    if (st->var_N){
        if (!pfvi_var_scratch(st, st->var_N)){
            pfvi_report(r, st);
            return;
        }
        if (!pfvi_var_map(r, st)){
            pfvi_error(r, "pfvi: the %zu variational configurations do not describe the N_var = %zu variational "
                    "particles of the N = %zu particles, each in one configuration (particles added after a "
                    "variation? a configuration's index or order edited?); step not taken.",
                    r->N_var_config, r->N_var, N);
            return;
        }
    }
    if (st->var_N && !pfvi_var_start_finite(r, st, r->t)){
        // Checked before anything is changed: t and every particle, real
        // and variational, are as they were.
        pfvi_report(r, st);
        return;
    }
    r->gravity_ignore_terms = REB_GRAVITY_IGNORE_TERMS_NONE;
    struct pfvi_call c;
    enum pfvi_glue state = glue_entry(r, st, &c);
    while (state != PFVI_GLUE_DONE){
        switch (state){
            case PFVI_GLUE_TAKE_UP:     state = glue_take_up(r, st, &c); break;
            case PFVI_GLUE_START:       state = glue_start(r, st, &c, N); break;
            case PFVI_GLUE_SHOW_INSIDE: state = glue_show_inside(r, st, &c, N); break;
            case PFVI_GLUE_STEP:        state = glue_step(r, st, &c, N); break;
            case PFVI_GLUE_SHOW_PASSED: state = glue_show_passed(r, st, &c, N); break;
            default:                    state = PFVI_GLUE_DONE; break;
        }
    }
}

static void pfvi_step_once(struct reb_simulation* r, struct pfvi_state* st);

// A refused step leaves t and every particle as they were; REBOUND's step
// then goes on with what follows the integrator's part: the user's
// post-timestep modifications (REBOUNDx's operators among them), the ODEs
// over dt_last_done, the collision search and its resolve functions, the
// heartbeat. Each would act on the restored state as though a step had been
// taken (a mass changed, overlapping bodies merged, an ODE advanced over
// the step before again: a hostile trial). So a refusal ends the call
// (status GENERIC_ERROR, which steps() did not see: it went on refusing
// step after step), sets dt_last_done to 0 (REBOUND's own "the step
// failed"), and holds those hooks, as the integrator's synchronize
// gives back when REBOUND ends the call. (Not for a step asked for from a
// callback inside a running step: that step owns the state and the hooks.)
static void pfvi_step(struct reb_simulation* r, void* state){
    struct pfvi_state* const st = state;
    if (!st){
        reb_simulation_error(r, "pfvi: integrator state missing (allocation failed).");
        return;
    }
    const int nested = (st->in_step != PFVI_STEP_IDLE);
    if (!nested && st->hooks_held && r->status == REB_STATUS_GENERIC_ERROR){
        // The call that refused goes on (rebound before 5.2 runs all of
        // steps(n) whatever the status): no step, and no second error,
        // until it ends and REBOUND synchronizes.
        return;
    }
    if (!nested){
        hooks_release(r, st);
    }
    const struct pfvi_error_mark errors = pfvi_rebound_errors(r);
    const double t = r->t;
    pfvi_step_once(r, st);
    // Refused: an error said and t where it was. (A step asked for from a
    // callback was refused with an error while the running step went on:
    // that step's t moved. A callback that switched the integrator freed st
    // at the step's end.)
    if (!nested && r->integrator.state == state && r->t == t && pfvi_rebound_error_since(r, errors)){
        r->status = REB_STATUS_GENERIC_ERROR;
        r->dt_last_done = 0.;
        hooks_hold(r, st);
    }
}

static void pfvi_step_once(struct reb_simulation* r, struct pfvi_state* st){
    if (st->in_step != PFVI_STEP_IDLE){
        // steps() or integrate() from a callback during a step: the running
        // step owns the state.
        reb_simulation_error(r, "pfvi: a step was asked for while one is running (steps() or integrate() "
                "called from a callback during a step); not taken. The running step goes on.");
        st->reentry_refused = 1;
        return;
    }
    st->in_step = PFVI_STEP_RUNNING;
    if (!st->request_set){
        // sim.steps() (no integrate() is running): between calls. A
        // simulation loaded from a snapshot written between calls judges its
        // sim.dt here as on an integrate() (pfvi_request_begin), and so does
        // a copy made after steps() (before, both took the value for the
        // snapshot's: a copy's first step 0.69 where its original's was the
        // 0.01 set on both; a hostile trial).
        st->snapshot_between_calls = st->end_N == 0 && st->dt_proposed != 0. && st->in_call == PFVI_CALL_BETWEEN;
    }
    st->in_call = st->request_set ? PFVI_CALL_INSIDE : PFVI_CALL_BETWEEN;
    st->reentry_refused = 0;
    st->request_shown = 0;
    st->status_at_start = (int)r->status;
    st->dt_at_start = r->dt;
    st->step_N = r->N;
    // What REBOUND restores sim.dt to after a finish on time (its
    // last_full_dt): the dt_last_done it saw before the first finishing step,
    // or, if that was the call's first step, the dt the call began with
    // (what the last call left, unless the user set one since: then the
    // user's, honoured either way).
    const int finishing = (r->status == REB_STATUS_LAST_STEP);
    // A loaded or copied simulation's call that begins on REBOUND's cut (its
    // snapshot written as REBOUND finished on an output: sim.dt the cut,
    // dt_last_done the run's step before it, which integrate() reset): as
    // the run it continues, whose last full step that was (request_end
    // leaves it as sim.dt where REBOUND restores the cut).
    // (Not a copy or snapshot written between calls: its sim.dt is the
    // simulation's own, and its bookkeeping the run's.)
    const int loaded_start = finishing && r->dt_last_done == 0. && st->end_N == 0 && st->request_set
        && !st->snapshot_between_calls;
    const int loaded_cut = loaded_start && !st->last_finishing && st->request_dt_last_done != 0.;
    const int loaded_cut_again = loaded_start && st->last_finishing && st->request_began_last_step
        && st->dt_rebound_leaves != 0.;
    const int loaded_entry_cut = loaded_start && st->request_entry_cut != 0.;
    if (loaded_cut || loaded_cut_again || loaded_entry_cut){
        st->request_dt_restore = loaded_entry_cut ? st->request_entry_cut
            : fabs(loaded_cut ? st->request_dt_last_done : st->dt_rebound_leaves);
    }
    st->request_loaded_cut = st->request_loaded_cut || loaded_cut || loaded_cut_again || loaded_entry_cut;
    if (finishing && !st->last_finishing && r->dt_last_done != 0.){
        st->dt_rebound_raw = fabs(r->dt_last_done);   // (what REBOUND keeps as its last full step)
    }
    if (finishing && !st->last_finishing && (r->dt_last_done != 0. || loaded_cut)){
        st->dt_rebound_leaves = loaded_cut ? st->request_dt_last_done : r->dt_last_done;
        // (REBOUND restores that, not the value the call began with.)
        st->dt_call_began = 0.;
        st->dt_call_default = 0;
        st->dt_call_first_cut = 0;
    }
    st->last_finishing = finishing;
    // What this call began with, if a call began here, and whether it was
    // pfvi's own (read before the step changes the proposal).
    const int call_start = (r->dt_last_done == 0.), loaded = (st->end_N == 0);
    const int fresh = loaded && st->dt_proposed == 0.;   // a new simulation: no step yet, none loaded
    st->call_is_integrate = call_start;
    // (Mid-run, sim.dt is the proposal: the rest is not asked.)
    const int began_proposed = st->dt_proposed != 0. && fabs(r->dt) == fabs(st->dt_proposed);
    const int began_default = !began_proposed && st->dt_proposed == 0. && r->dt == PFVI_REBOUND_DT_DEFAULT;
    const int began_restored_own = !began_proposed && !began_default && rebound_restored(r, st, 0);
    const int began_restored_default = !began_proposed && !began_default && !began_restored_own
        && rebound_restored(r, st, 1);
    if (!finishing && (!loaded || st->snapshot_between_calls) && r->dt != 0. && !(began_proposed || began_default || began_restored_own
            || began_restored_default)){
        st->dt_user = fabs(r->dt);
        st->dt_user_spent = 0;
    }
    // (REBOUND cut from what it synchronized with: at least the cut, the same way.)
    const int cut_from_known = st->dt_at_sync*st->dt_at_start > 0. && fabs(st->dt_at_sync) >= fabs(st->dt_at_start);
    st->dt_first_uncut = (call_start && finishing && fresh && cut_from_known) ? st->dt_at_sync : 0.;
    pfvi_step_model_keep(r, st);
    const uint64_t steps_before = st->statistics.n_steps;
    pfvi_step_take(r, st);
    st->dt_first_uncut = 0.;
    if (!finishing && st->statistics.n_steps != steps_before && st->dt_user != 0.
            && fabs(st->dt_at_start) == st->dt_user && fabs(r->dt_last_done) == st->dt_user){
        st->dt_user_spent = 1;
    }
    if (call_start && !finishing){
        const int own = began_proposed || began_restored_own;
        const int by_default = !own && (began_default || began_restored_default);
        st->dt_call_began = (own || by_default) ? st->dt_at_start : 0.;
        st->dt_call_default = by_default;
        st->dt_call_first_cut = 0;
        st->dt_call_cut = 0.;
    }else if (call_start && finishing && loaded && !loaded_cut && !st->snapshot_between_calls
            && st->request_entry_cut == 0.){
        // (A snapshot written between calls or at a call's start holds its own
        // sim.dt, or the value the call began with, which REBOUND cut here and
        // restores after the call, as in the run it copies.)
        st->dt_call_cut = st->dt_at_start;
        if (fresh && cut_from_known && fabs(st->dt_at_sync) == PFVI_REBOUND_DT_DEFAULT){
            // REBOUND cut a new simulation's 0.001 to a time within it, and
            // restores 0.001 after the call: not a cap of the user's (before,
            // the next call took it for one and cut the run's first step:
            // Kepler e = 0.5, 29 steps against one call's 27, 2e-10 apart).
            // (A user's own 0.001 there is the value the simulation holds;
            // a call that began with another value of the user's leaves that
            // restored, and a 0.001 set after it is the user's: a hostile
            // trial.)
            st->dt_call_began = PFVI_REBOUND_DT_DEFAULT;
            st->dt_call_default = 1;
            st->dt_call_first_cut = 1;
        }
    }
    // (A later call whose first step is its last began with what the call
    // before left: what is known of it stands.)
    if (!finishing){
        st->dt_rebound_leaves = r->dt;   // REBOUND keeps what the step left
    }
    if (st->request_shown && st->request_dt_leaves != 0.){
        // Shown on the requested time where REBOUND's finish would have come
        // after the state past it: what that finish knows (as at its first
        // finishing step, above); pfvi_request_end leaves it as sim.dt.
        st->dt_rebound_leaves = st->request_dt_leaves;
    }
    pfvi_step_model_apply_pending(r, st);
    st->in_step = PFVI_STEP_IDLE;
    if (st->free_pending){
        pfvi_state_free(st);
    }
}

int pfvi_register(void){
    // REBOUND 5.2.2 hangs on a second custom registration in one process, and
    // refuses a duplicate name only after that loop: look the name up first.
    static int registered = 0;
    if (registered){
        return 0;
    }
    char** names = reb_integrators_registered();
    int found = 0;
    for (size_t i=0; names && names[i]; i++){
        if (strcmp(names[i], PFVI_NAME) == 0){
            found = 1;
        }
    }
    free(names);
    registered = 1;
    if (found){
        return 0;
    }
    reb_integrator_register(pfvi_integrator, PFVI_NAME);
    return 1;
}

const char* pfvi_option_value_name(const char* field, int i){
    const struct reb_binarydata_enum_descriptor* values =
        !strcmp(field, "fitting") ? pfvi_fitting_enum :
        !strcmp(field, "frequency") ? pfvi_frequency_enum :
        !strcmp(field, "step_control") ? pfvi_step_control_enum :
        !strcmp(field, "centre") ? pfvi_centre_enum : NULL;
    for (int k=0; values && values[k].name[0]; k++){
        if (k == i){
            return values[k].name;
        }
    }
    return NULL;
}

// The pairs' field of r for the two inspection entry points below (called
// from Python, not per step): the integrator's own pfvi_field_of on a scratch
// state, and a partner slot per particle; 0 if out of memory. The caller frees
// *partners and scratch->images.
static int pfvi_inspection_field(struct reb_simulation* r, struct pfvi_state* scratch, struct pfvi_field* field,
    struct pfvi_partner** partners){
    *scratch = (struct pfvi_state){0};
    *partners = malloc((r->N ? r->N : 1)*sizeof(**partners));
    if (!*partners || !pfvi_field_of(r, scratch, field)){
        free(*partners);
        free(scratch->images);
        return 0;
    }
    return 1;
}

int pfvi_partners(struct reb_simulation* r, size_t* out){
    const size_t N = r->N;
    struct pfvi_state scratch;
    struct pfvi_field field;
    struct pfvi_partner* partners;
    if (!pfvi_inspection_field(r, &scratch, &field, &partners)){
        return 0;
    }
    pfvi_partner_search(r->particles, N, &field, partners);
    for (size_t i=0; i<N; i++){
        out[i] = (partners[i].j == SIZE_MAX) ? N : partners[i].j;
    }
    free(partners);
    free(scratch.images);
    return 1;
}

int pfvi_two_alone(struct reb_simulation* r){
    return pfvi_gravity_two_alone(r, r->N);
}

int pfvi_density_of(struct reb_simulation* r, int stages, double* out){
    if (stages < PFVI_STAGES_MIN || stages > PFVI_STAGES_MAX){
        return 0;
    }
    struct pfvi_state scratch;
    struct pfvi_field field;
    struct pfvi_partner* partners;
    if (!pfvi_inspection_field(r, &scratch, &field, &partners)){
        return 0;
    }
    reb_simulation_update_acceleration(r);
    const int paired = pfvi_step_density(r->particles, NULL, r->N, &field, stages, partners, &out[0], &out[1], NULL);
    free(partners);
    free(scratch.images);
    return paired;
}

static struct pfvi_state* pfvi_state_of(struct reb_simulation* r){
    return (r->integrator.callbacks.step == pfvi_step) ? r->integrator.state : NULL;
}

// The options as the next step checks them, before any step (compare's
// settings check theirs when made): 1 valid; 0 with pfvi's error among
// REBOUND's messages; -1 if the integrator is not pfvi.
int pfvi_options_check(struct reb_simulation* r){
    struct pfvi_state* const st = pfvi_state_of(r);
    return st ? pfvi_options_valid(r, &st->settings) : -1;
}

// What pfvi_request_end leaves as sim.dt where REBOUND restored dt after
// a call, with the bookkeeping it updates (also replayed for a snapshot
// REBOUND wrote at a call's end, before this ran: pfvi_request_begin).
static double request_end_dt(struct pfvi_state* st, double dt){
    if (st->request_dt_leaves != 0.){
        // The call ends: sim.dt as REBOUND's own finish on the time leaves it.
        dt = st->request_dt_leaves;
    }else if (st->request_loaded_cut && fabs(dt) != st->request_dt_restore){
        // REBOUND restored the cut a loaded simulation's call began on (its
        // last full step, to REBOUND); the run it continues had its step
        // before the cut restored. Taken as a cap, the cut made a restarted
        // archive of a run with a timestep hook or a heartbeat that edits
        // every step, and outputs, take a step the run did not (4 of 12
        // snapshots off, 1.6e-2: a hostile trial).
        dt = copysign(st->request_dt_restore, dt);
    }
    if (st->dt_user_spent && fabs(dt) == st->dt_user && st->dt_proposed != 0. && fabs(st->dt_proposed) != st->dt_user){
        // REBOUND restored a user's cap that a step took in full (the call's
        // last full step): left as it is, the next call could not tell it
        // from the user setting it again, and either every later call's
        // first step was capped (200 steps at 100 outputs for one call's 5,
        // the run 1e-11 off) or a user's sim.dt before each call was not. The
        // run's proposal stands instead, pfvi's own: what a run that the cap
        // did not end on leaves.
        dt = copysign(st->dt_proposed, dt);
        st->dt_rebound_leaves = dt;
    }
    return dt;
}

double pfvi_request_begin(struct reb_simulation* r, double t){
    struct pfvi_state* const st = pfvi_state_of(r);
    if (!st){
        return NAN;
    }
    // (an enclosing call's, returned to be given back: a callback's integrate() is refused)
    const double held = st->request_set ? st->request_t : NAN;
    if (!st->request_set){
        // What the snapshot says of itself (a loaded or copied simulation's),
        // read before this call overwrites it.
        const int loaded = st->end_N == 0 && st->dt_proposed != 0.;
        if (loaded && st->in_call == PFVI_CALL_INSIDE && r->status == REB_STATUS_SUCCESS && r->exact_finish_time == 1
                && st->dt_rebound_raw != 0.){
            // A snapshot REBOUND wrote at a call's end, after restoring sim.dt
            // and before pfvi's end of the call: that end now, as the run
            // had it before its next call (unless the user set sim.dt since),
            // and the simulation is between calls (before, its restore was
            // taken for the user's: 10 of 244 restarts off; the second
            // hostile trial of 2026-11-29).
            const double left = request_end_dt(st, copysign(st->dt_rebound_raw, r->dt));
            r->dt = (fabs(r->dt) == fabs(st->dt_rebound_raw)) ? left : r->dt;
            st->in_call = PFVI_CALL_BETWEEN;
        }
        st->dt_rebound_raw = fabs(r->dt);   // (REBOUND's restore unless a finish takes a last full step)
        const int cut_start = (st->in_call == PFVI_CALL_STARTING_CUT);
        const int last_step = (r->status == REB_STATUS_LAST_STEP) || cut_start;
        st->in_call = cut_start ? PFVI_CALL_STARTING : st->in_call;
        // (A call's start where REBOUND cut sim.dt to finish holds the cut, not
        // the user's value: judged as a cut where the restart's call does not
        // finish there, request_entry_cut where it does.)
        st->snapshot_between_calls = loaded && (st->in_call == PFVI_CALL_BETWEEN
            || (st->in_call == PFVI_CALL_STARTING && !last_step));
        st->request_began_last_step = last_step && st->in_call == PFVI_CALL_INSIDE;
        st->request_entry_cut = (loaded && last_step && st->in_call == PFVI_CALL_STARTING) ? fabs(st->dt_call_entry) : 0.;
        // (there, the call the snapshot began: the value it began with)
        st->dt_call_entry = (st->request_entry_cut != 0.) ? copysign(st->request_entry_cut, r->dt) : r->dt;
        st->in_call = PFVI_CALL_STARTING;
    }
    st->request_set = 1;
    st->request_t = t;
    st->request_dt_leaves = 0.;
    st->request_dt_last_done = r->dt_last_done;   // (REBOUND's integrate() resets it)
    st->request_loaded_cut = 0;
    return held;
}

void pfvi_request_end(struct reb_simulation* r, double held){
    struct pfvi_state* const st = pfvi_state_of(r);
    if (!st){
        return;
    }
    if (st->request_set && r->exact_finish_time == 1 && st->in_step == PFVI_STEP_IDLE){
        r->dt = request_end_dt(st, r->dt);
    }
    st->request_loaded_cut = 0;
    st->request_dt_leaves = 0.;
    st->request_set = !isnan(held);
    st->request_t = st->request_set ? held : 0.;
    // A call that took no step (integrate() to the time it is at) on a
    // simulation loaded from a call's start where REBOUND had cut sim.dt:
    // still that snapshot, its sim.dt the cut (a hostile trial: taken for
    // the user's at the next call, 3.4e-2 off). (dt_call_entry holds the
    // value that call began with, as pfvi_request_begin set it.)
    const int unstepped_cut = !st->request_set && st->in_call == PFVI_CALL_STARTING && st->request_entry_cut != 0.;
    st->in_call = unstepped_cut ? PFVI_CALL_STARTING_CUT : (st->request_set ? PFVI_CALL_INSIDE : PFVI_CALL_BETWEEN);
    st->snapshot_between_calls = st->snapshot_between_calls && st->request_set;
    st->request_entry_cut = st->request_set ? st->request_entry_cut : 0.;
}

const char* pfvi_rebound_version_compiled(void){
    return PFVI_REBOUND_VERSION;
}

size_t pfvi_sizeof_simulation(void){
    return sizeof(struct reb_simulation);
}

void pfvi_stages_range(int* min, int* max){
    *min = PFVI_STAGES_MIN;
    *max = PFVI_STAGES_MAX;
}

size_t pfvi_sizeof_particle(void){
    return sizeof(struct reb_particle);
}
