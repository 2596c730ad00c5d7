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
// Fixed-point iterations allowed for the implicit final kick when the force
// depends on velocities.
#define PFVI_VDEP_MAX_ITERATIONS 16

enum pfvi_fitting {
    PFVI_FITTING_PHASE = 0,          // seed's Ld divided by gamma(u): exact q and p on the oscillator
    PFVI_FITTING_PHASE_LITERAL = 1,  // seed's Ld exactly as printed: momenta scaled by gamma(u)
    PFVI_FITTING_NONE = 2,           // classical Marsden-West trapezoidal Ld (velocity Verlet)
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

// What the next step needs of the last one: position and velocity (compared
// bitwise, in the order of struct reb_particle), mass, and the acceleration.
struct pfvi_end_state {
    double xv[6];
    double m;
    double a[3];
};

struct pfvi_compensation {
    double x[3];
    double v[3];
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
    // Statistics
    uint64_t n_steps;
    uint64_t n_u_limited;
    uint64_t n_force_evaluations;
    double omega_min;
    double omega_max;
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
    size_t cache_N;                // >0: `end` describes the particles, taken at cache_t with cache_G
    double cache_t;
    double cache_G;
};

// pfvi_fitting.c
enum pfvi_fit_status { PFVI_FIT_OK = 0, PFVI_FIT_LIMITED = 1, PFVI_FIT_POLE = -1 };
PFVI_INTERNAL enum pfvi_fit_status pfvi_two_point_fit(double omega, double h, double u_max,
        int literal, struct pfvi_two_point* fit);
PFVI_API void pfvi_seed_coefficients(double u, double c, double out[4]);
PFVI_API double pfvi_gamma(double u);
PFVI_API int pfvi_two_point_coefficients(double omega, double h, double u_max, int literal, double out[6]);

// pfvi_frequency.c
PFVI_INTERNAL double pfvi_curvature_frequency(const double v[3], const double a[3]);

// pfvi_integrator.c
extern const struct reb_integrator pfvi_integrator;
PFVI_API int pfvi_register(void);
PFVI_API const char* pfvi_rebound_version_compiled(void);
PFVI_API size_t pfvi_sizeof_simulation(void);
PFVI_API size_t pfvi_sizeof_particle(void);

#endif // PFVI_H
