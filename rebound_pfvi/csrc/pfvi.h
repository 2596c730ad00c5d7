/**
 * pfvi.h: internal declarations of the phase-fitted discrete Lagrangian
 * integrator (Kosmas & Vlachos, "Phase-fitted Discrete Lagrangian
 * Integrators"). Only the symbols marked PFVI_API are exported; everything
 * else in the core is static or internal to the library.
 */
#ifndef PFVI_H
#define PFVI_H

#include <stddef.h>
#include <stdint.h>
#include "rebound.h"

#define PFVI_API __attribute__((visibility("default")))
#define PFVI_INTERNAL __attribute__((visibility("hidden")))

// Name under which the integrator is registered with REBOUND. Lower case:
// REBOUND's Python setter lower-cases integrator names.
#define PFVI_NAME "pfvi"

// Default bound on u = omega*h (docs/method.md, "Singularities and u_max").
#define PFVI_U_MAX_DEFAULT 1.0
// A step is refused when u lies within this distance (in cos u or sin u) of a
// pole of the two-point coefficients: cos u = 0 (all fitted modes) and
// sin u = 0 away from u = 0 (phase-literal, through gamma = u cot u).
#define PFVI_POLE_GUARD 1e-3
// Largest fitted frequency: the two-point step needs omega^2 (and omega^2 q),
// which leave the doubles above omega ~ 1.3e154. A larger omega (a body
// almost at rest turning sharply, or u_max/|dt| for a tiny dt) is fitted as 0,
// the classical scheme, and counted in n_u_limited.
#define PFVI_OMEGA_MAX 1e150
// A macro's value as a string, for the field documentation.
#define PFVI_STR_(x) #x
#define PFVI_STR(x) PFVI_STR_(x)
// Fixed-point iterations allowed for the implicit final kick when the force
// depends on velocities.
#define PFVI_VDEP_MAX_ITERATIONS 16
// Gauss-Lobatto discrete Lagrangians with interior corrections (seed section 6).
#define PFVI_STAGES_MIN 2
#define PFVI_STAGES_MAX 6
#define PFVI_STAGES_DEFAULT 4
// The stage solve: fixed-point iterations per step at most, and the largest
// relative change of the stage values at which a solve that stops decreasing
// is accepted as converged to round-off (larger: the step is refused).
#define PFVI_STAGE_MAX_ITERATIONS 50
#define PFVI_STAGE_TOLERANCE 1e-12
// Step control (seed section 4, pfvi_control.c).
#define PFVI_EPSILON_DEFAULT 1e-6
// Standard controller: next h = h * SAFETY * (epsilon/error)^(1/ORDER), the
// factor kept within [SHRINK_MIN, GROW_MAX]; ORDER is the measured order in h
// of the osculating-circle estimate (docs/adaptive.md).
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

enum pfvi_fitting {
    PFVI_FITTING_PHASE = 0,          // seed's Ld divided by gamma(u): exact q and p on the oscillator
    PFVI_FITTING_PHASE_LITERAL = 1,  // seed's Ld exactly as printed: momenta scaled by gamma(u)
    PFVI_FITTING_NONE = 2,           // classical Marsden-West trapezoidal Ld (velocity Verlet)
};

enum pfvi_step_control {
    PFVI_STEP_CONTROL_SEED = 0,       // accept if the estimate <= epsilon, propose the next h (seed section 4)
    PFVI_STEP_CONTROL_REVERSIBLE = 1, // h solves estimate(y_n, y_n+1) = epsilon: symmetric in the two ends
};

enum pfvi_frequency {
    PFVI_FREQUENCY_CURVATURE = 0,    // seed eq. (freq): omega = |v x a| / |v|^2, per particle
    PFVI_FREQUENCY_FIXED = 1,        // the field `omega`, for every particle
};

// The two-point phase-fitted discrete Lagrangian of one particle over one
// step, in the form in which its position-momentum equations are solved:
// kick with the residual force, rotate with the harmonic flow at omega,
// kick again (docs/method.md derives it from the seed's b, bbar, B, Bbar).
struct pfvi_two_point {
    double omega;        // fitted frequency after limiting
    double keep;         // 1 if cos u > 0, else cos u: q1 = keep q + ((cos u - keep) q + ...)
    double cos_u_m_keep; // cos(u) - keep, computed without cancellation
    double h_sinc_u;     // h sin(u)/u  (= sin(u)/omega)
    double omega_sin_u;  // omega sin(u)
    double half_kick;    // (h/2) tan(u)/u: weight of the residual force a + omega^2 q
    double gamma;        // phase-literal: gamma(u) = u cot u, its momentum scale; otherwise 1
};

// Gauss-Lobatto quadrature on [0, 1] (seed section 3, maximal order): nodes
// c^1 = 0 < ... < c^s = 1, weights w_j with sum_j w_j (c^j)^l = 1/(l+1) for
// l <= 2s - 3, and the differentiation matrix of the interpolating polynomial,
// a[k][j] = l_j'(c^k), with sum_j a^k_j = 0 and sum_j a^k_j (c^j)^n = n (c^k)^(n-1)
// (seed section 6). Computed, not tabulated: pfvi_lobatto.c.
struct pfvi_lobatto {
    int s;
    double c[PFVI_STAGES_MAX];
    double w[PFVI_STAGES_MAX];
    double a[PFVI_STAGES_MAX][PFVI_STAGES_MAX];
    double det_classical;   // determinant of the stage matrix at u = 0 (singularity guard)
};

// One particle's s-stage discrete Lagrangian over one step, u = omega h: the
// fitted interpolation of the seed (b, bbar, B, Bbar at every node), written
// with the cancellation-free combinations beta_m = b + bbar - 1 and beta_d =
// B + Bbar, the momentum normalisation G, and the LU factors of the matrix of
// the linear (kinetic) part of the equations p_k = -D1 Ld, dLd/d(delta q^j) = 0
// in the unknowns (q_k+1 - q_k, delta q^2, ..., delta q^s-1).
struct pfvi_stage_fit {
    double omega;
    double G;                         // -D1 Ld_printed = G p_k: gamma_s(u) for "phase", else 1
    double b[PFVI_STAGES_MAX];
    double bbar[PFVI_STAGES_MAX];
    double B[PFVI_STAGES_MAX];
    double Bbar[PFVI_STAGES_MAX];
    double beta_m[PFVI_STAGES_MAX];
    double beta_d[PFVI_STAGES_MAX];
    double q0_row[PFVI_STAGES_MAX-1]; // coefficient of q_k in each equation
    double lu[PFVI_STAGES_MAX-1][PFVI_STAGES_MAX-1];
    int pivot[PFVI_STAGES_MAX-1];
};

// What the next step needs of the last one: position and velocity (compared
// bitwise, in the order of struct reb_particle), mass, and the acceleration.
struct pfvi_end_state {
    double xv[6];
    double m;
    double a[3];
};

// The osculating circle of one particle at one point of its path: radius R
// and centre O = x + offset (seed section 4). defined = 0 on a straight line
// or at rest, where the curvature vanishes.
struct pfvi_osculating {
    double R;
    double offset[3];
    double binormal[3];  // (v x a) / |v x a|: the normal of the circle's plane
    double omega;        // |v x a| / |v|^2, the curvature frequency
    int defined;
};

struct pfvi_compensation {
    double x[3];
    double v[3];
};

// Everything besides the particles, N and t that REBOUND's force evaluation
// reads (gravity.c, boundary.c, the force hooks), kept with the last step's
// end acceleration: that acceleration is reused only if this is unchanged,
// bit for bit. Filled by pfvi_force_model_of, padding zeroed, so that it
// compares with memcmp.
struct pfvi_force_model {
    double G;
    double softening;
    double opening_angle2;
    double root_size;
    size_t N_root[3];
    double OMEGA;
    double OMEGAZ;
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

// Integrator state. Options and statistics are REBOUND fields (saved in
// Simulationarchives); the scratch part is not saved and grows only with N.
struct pfvi_state {
    // Options
    int fitting;
    int frequency;
    int stages;
    double omega;
    double u_max;
    double epsilon;
    int step_control;
    // Statistics
    uint64_t n_steps;
    uint64_t n_iterations;
    uint64_t iterations_max;
    double iterations_mean;
    uint64_t n_u_limited;
    uint64_t n_force_evaluations;
    double omega_min;
    double omega_max;
    uint64_t n_rejected;
    uint64_t n_attempts;
    uint64_t n_asymmetric;
    double error_estimate;         // the step control's estimate for the last step taken
    // Controller state (saved): the last solution of the reversible step equation.
    double dt_reversible;
    // Scratch
    size_t N_allocated;
    struct reb_particle* start;    // bit-exact copy of the particles at the start of the step (rollback)
    struct pfvi_end_state* end;    // end of the last step, with its accelerations (force reuse)
    struct pfvi_two_point* fit;    // per-particle coefficients of the current step
    struct reb_vec3d* v_rotated;   // velocities before the final kick (velocity-dependent forces)
    struct reb_vec3d* dx;          // position increment of the step, with the carried low-order part
    struct reb_vec3d* dv;          // velocity increment of the step, with the carried low-order part
    // Compensated summation: the low-order parts of x, y, z, vx, vy, vz that
    // the particles' doubles lost (Kahan). Saved in Simulationarchives, so a
    // continued run stays bit-identical.
    struct pfvi_compensation* compensation;
    size_t N_compensation;
    // Step control: the frequency each particle is fitted to in this step,
    // the curvature frequency at its end (the controller's u bound), and
    // the osculating circles at its start.
    double* omega_fit;
    double* omega_end;
    struct pfvi_osculating* osculating_start;
    // What a trial step found, committed only if the step is taken.
    uint64_t trial_n_limited;
    uint64_t trial_rounds;
    double trial_change;           // the stage solve's last relative change
    double trial_omega_min;
    double trial_omega_max;
    // The s-stage solve (stages >= 3): quadrature, per-particle fits, stage
    // accelerations a[i][k] of the step being tried, those of the last step
    // taken (the predictor's data), and the unknowns of the current and the
    // next iterate.
    struct pfvi_lobatto lobatto;
    struct pfvi_stage_fit* stage_fit;
    double (*stage_a)[PFVI_STAGES_MAX][3];
    double (*predictor_a)[PFVI_STAGES_MAX][3];
    double (*unknowns)[PFVI_STAGES_MAX-1][3];
    double (*unknowns_next)[PFVI_STAGES_MAX-1][3];
    // The last step's stage accelerations seed the next solve if it starts
    // where that step ended (same s, N and t). Saved in Simulationarchives
    // with predictor_a, so that a continued run is bit-identical.
    int predictor_stages;          // s of that step (0: none)
    size_t predictor_N;
    double predictor_h;
    double predictor_t;            // t at its end
    size_t cache_N;                // >0: `end` describes the particles, taken at cache_t under cache_model
    double cache_t;
    struct pfvi_force_model cache_model;
    // Particles added or removed by a callback during a step (a force
    // evaluation): origin[k] is the index at the step's start of the particle
    // now at k, or SIZE_MAX for one added since, so that a refused step can
    // restore every particle that is still there. Tracked only while a step
    // runs, set up at the first change (the hot path never touches it).
    int in_step;
    size_t step_N;
    size_t* origin;
    size_t origin_N;
    size_t origin_allocated;
};

// pfvi_fitting.c
enum pfvi_fit_status { PFVI_FIT_OK = 0, PFVI_FIT_LIMITED = 1, PFVI_FIT_POLE = -1 };
// |u| = |omega h| above u_max is limited to u_max (omega reduced to match).
PFVI_INTERNAL enum pfvi_fit_status pfvi_limit_u(double* omega, double h, double u_max, double* u);
PFVI_INTERNAL enum pfvi_fit_status pfvi_two_point_fit(double omega, double h, double u_max,
        int literal, struct pfvi_two_point* fit);
PFVI_API void pfvi_seed_coefficients(double u, double c, double out[4]);
PFVI_API double pfvi_gamma(double u);
PFVI_API int pfvi_two_point_coefficients(double omega, double h, double u_max, int literal, double out[6]);

// pfvi_lobatto.c
PFVI_INTERNAL int pfvi_lobatto_compute(int s, struct pfvi_lobatto* q);
PFVI_INTERNAL enum pfvi_fit_status pfvi_stage_fit(const struct pfvi_lobatto* q, double omega, double h,
        double u_max, int fitting, struct pfvi_stage_fit* fit);
PFVI_API int pfvi_lobatto_table(int s, double* c, double* w, double* a);
PFVI_API double pfvi_gamma_stages(int s, double u);
PFVI_API int pfvi_stage_coefficients(int s, double u, double* out);

// Outcome of one trial step. A trial leaves the end state in the particles
// and commits nothing; on anything but PFVI_TRIAL_OK the particles and t are
// already rolled back.
enum pfvi_trial {
    PFVI_TRIAL_OK = 1,
    PFVI_TRIAL_ERROR = 0,            // refused, error reported
    PFVI_TRIAL_NOT_CONVERGED = -1,   // the stage solve did not converge; no error reported
};

// pfvi_stages.c
PFVI_INTERNAL enum pfvi_trial pfvi_stages_trial(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0, double h);
PFVI_INTERNAL void pfvi_stages_commit(struct reb_simulation* r, struct pfvi_state* s, size_t N, double h);

// pfvi_control.c
PFVI_INTERNAL void pfvi_osculating_circle(const double v[3], const double a[3], struct pfvi_osculating* c);
// The seed's bound | |R1 - R2| - |O1 - O2| | on the position error of particle
// i's step, relative to min(R1, R2), less its round-off level *noise (never < 0).
// Meaningless across an inflection: pfvi_control.c leaves such particles out.
PFVI_INTERNAL double pfvi_osculating_error(const struct reb_particle* p0, const struct pfvi_osculating* c0,
        const struct reb_particle* p1, const struct pfvi_osculating* c1, double* noise);
// Takes one step with the controller of s->step_control; returns the h taken,
// or 0 (rolled back, error reported) if none could be.
PFVI_INTERNAL double pfvi_controlled_step(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0);
// pfvi_integrator.c: one trial step of either scheme, and its commit.
PFVI_INTERNAL enum pfvi_trial pfvi_trial_step(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0, double h);
PFVI_INTERNAL void pfvi_commit_step(struct reb_simulation* r, struct pfvi_state* s, size_t N, double h);

// pfvi_integrator.c, shared with pfvi_stages.c
PFVI_INTERNAL void pfvi_error(struct reb_simulation* r, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
PFVI_INTERNAL void pfvi_roll_back(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0);
PFVI_INTERNAL int pfvi_update_acceleration(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0);
PFVI_INTERNAL int pfvi_particle_finite(const struct reb_particle* p);

// pfvi_frequency.c
// The curvature of a path with velocity v and acceleration a, computed from
// v and a scaled by powers of two, so that no intermediate over- or
// underflows: omega = |v x a|/|v|^2, R = |v|^3/|v x a| (each may still be 0
// or Inf where the true value lies outside the doubles), and the unit normal
// (towards the centre) and binormal. Returns 0, with omega = 0 and R = Inf,
// at rest or on a straight line.
struct pfvi_curvature {
    double omega;
    double R;
    double normal[3];
    double binormal[3];
};
PFVI_INTERNAL int pfvi_curvature_scaled(const double v[3], const double a[3], struct pfvi_curvature* k);
PFVI_INTERNAL double pfvi_curvature_frequency(const double v[3], const double a[3]);
// The omega a step fits particle p to (before limiting): 0 for fitting "none",
// the field omega for frequency "fixed", else the curvature frequency.
PFVI_INTERNAL double pfvi_step_frequency(const struct pfvi_state* s, const struct reb_particle* p, const double a[3]);

// pfvi_integrator.c
extern const struct reb_integrator pfvi_integrator;
PFVI_API int pfvi_register(void);
PFVI_API const char* pfvi_rebound_version_compiled(void);
PFVI_API size_t pfvi_sizeof_simulation(void);
PFVI_API size_t pfvi_sizeof_particle(void);

#endif // PFVI_H
