/**
 * pfvi_contact.c: contacts inside a step (docs/collisions.md).
 *
 * REBOUND looks for collisions after each step (reb_collision_search, after
 * the integrator's step and post_timestep_modifications: "direct" overlaps
 * at the step's end, approaching; "line" along straight segments back from
 * the end) and raises an Encounter (exit_min_distance) if a pair is closer
 * than the limit at a step's end (run_heartbeat). pfvi's steps are long, so
 * contacts fall between their ends. Each step's stages give every body's
 * path over the step: the polynomial x(tau), tau = (t - t0)/h in [0, 1], of
 * degree 2s through its positions and accelerations at the s nodes (the
 * mean of those through its velocity at either end). After a step is taken, the pairs whose paths
 * can come within the limit (boxes of each body's path between two nodes,
 * swept along x: O(s N log N + candidates), not O(N^2)) are searched along that polynomial
 * for the first time the separation falls below the sum of their radii
 * (collisions on) or exit_min_distance; if one does before the step's end,
 * the step is retaken (rolled back, the controller as before it) capped to
 * end just inside that contact (PFVI_CONTACT_DEPTH), so that REBOUND's own
 * search, its resolve functions and its Encounter see it at the step's end.
 * Such a step is not time-symmetric (n_contact_steps, n_asymmetric).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "pfvi.h"
#include "boundary.h"

int pfvi_contact_enabled(const struct reb_simulation* r){
    if (r->exit_min_distance > 0.){
        return 1;
    }
    if (r->collision == REB_COLLISION_NONE){
        return 0;
    }
    const struct reb_particle* const ps = r->particles;
    for (size_t i=0; i<r->N; i++){
        if (ps[i].r > 0.){
            return 1;
        }
    }
    return 0;
}


// Chebyshev T_n(z), T_n'(z), T_n''(z) for n < m.
static void chebyshev(double z, int m, double* T, double* dT, double* d2T){
    T[0] = 1.; dT[0] = 0.; d2T[0] = 0.;
    if (m > 1){
        T[1] = z; dT[1] = 1.; d2T[1] = 0.;
    }
    for (int n=1; n+1<m; n++){
        T[n+1] = 2.*z*T[n] - T[n-1];
        dT[n+1] = 2.*T[n] + 2.*z*dT[n] - dT[n-1];
        d2T[n+1] = 4.*dT[n] + 2.*z*d2T[n] - d2T[n-1];
    }
}

// The s nodes in [0, 1] of the step's stages.
static const double* contact_nodes(const struct pfvi_state* st){
    static const double two_point[2] = {0., 1.};
    return (st->options.stages == 2) ? two_point : st->rule.c;
}

// The inverse of the conditions on the m = 2s + 1 Chebyshev coefficients
// (z = 2 tau - 1) of a path through x at the s nodes, x'' (in tau) at the s
// nodes and x' (in tau) at the end `e` (0: start, 1: end), into inv[n][k].
// (With x' at both ends the 2s + 2 conditions on a polynomial of degree
// 2s + 1 are singular at Lobatto's symmetric nodes, s >= 3.)
static int contact_invert(const double* c, int s, int e, double inv[2*PFVI_STAGES_MAX+1][2*PFVI_STAGES_MAX+1]){
    const int m = 2*s + 1;
    double A[2*PFVI_STAGES_MAX+1][2*(2*PFVI_STAGES_MAX+1)];
    double T[2*PFVI_STAGES_MAX+2], dT[2*PFVI_STAGES_MAX+2], d2T[2*PFVI_STAGES_MAX+2];
    for (int k=0; k<s; k++){
        chebyshev(2.*c[k] - 1., m, T, dT, d2T);
        for (int n=0; n<m; n++){
            A[k][n] = T[n];
            A[s + k][n] = 4.*d2T[n];
        }
    }
    chebyshev(e ? 1. : -1., m, T, dT, d2T);
    for (int n=0; n<m; n++){
        A[2*s][n] = 2.*dT[n];
    }
    for (int k=0; k<m; k++){
        for (int n=0; n<m; n++){
            A[k][m + n] = (k == n);
        }
    }
    // Gauss-Jordan with partial pivoting.
    for (int col=0; col<m; col++){
        int p = col;
        for (int k=col+1; k<m; k++){
            p = (fabs(A[k][col]) > fabs(A[p][col])) ? k : p;
        }
        if (A[p][col] == 0.){
            return 0;
        }
        for (int n=0; n<2*m; n++){
            const double tmp = A[col][n]; A[col][n] = A[p][n]; A[p][n] = tmp;
        }
        const double inv_pivot = 1./A[col][col];
        for (int n=0; n<2*m; n++){
            A[col][n] *= inv_pivot;
        }
        for (int k=0; k<m; k++){
            if (k != col && A[k][col] != 0.){
                const double f = A[k][col];
                for (int n=0; n<2*m; n++){
                    A[k][n] -= f*A[col][n];
                }
            }
        }
    }
    for (int n=0; n<m; n++){
        for (int k=0; k<m; k++){
            inv[n][k] = A[n][m + k];
        }
    }
    return 1;
}

// The path of degree 2s from the step's data (x at the s nodes, h^2 a at
// the s nodes, h v at the start and at the end; 2s + 2 values): the mean of
// the interpolants through x, a and the start velocity and through x, a and
// the end velocity (symmetric in the step's direction), as the map
// contact_inverse[n][k] from the data to the Chebyshev coefficients.
static int contact_prepare(struct pfvi_state* st){
    const int s = st->options.stages, m = 2*s + 1;
    if (st->contact_s == s){
        return 1;
    }
    if (s > 2 && st->rule.s != s){
        return 0;
    }
    const double* const c = contact_nodes(st);
    double start[2*PFVI_STAGES_MAX+1][2*PFVI_STAGES_MAX+1], end[2*PFVI_STAGES_MAX+1][2*PFVI_STAGES_MAX+1];
    if (!contact_invert(c, s, 0, start) || !contact_invert(c, s, 1, end)){
        return 0;
    }
    for (int n=0; n<m; n++){
        for (int k=0; k<2*s; k++){
            st->contact_inverse[n][k] = 0.5*(start[n][k] + end[n][k]);
        }
        st->contact_inverse[n][2*s] = 0.5*start[n][2*s];
        st->contact_inverse[n][2*s+1] = 0.5*end[n][2*s];
    }
    st->contact_s = s;
    return 1;
}

// Body i's position and acceleration at node k of the step just taken, and
// its velocities at both ends (the committed step: s >= 3 keeps its stages
// in predictor_x and predictor_a; both ends from the particles).
static void contact_node(const struct reb_simulation* r, const struct pfvi_state* st, size_t i, int k,
        double x[3], double a[3]){
    const int s = st->options.stages;
    if (k == 0){
        const struct reb_particle* const p = &st->start[i];
        x[0] = p->x; x[1] = p->y; x[2] = p->z;
        a[0] = st->end[i].a[0]; a[1] = st->end[i].a[1]; a[2] = st->end[i].a[2];
    }else if (k == s - 1){
        const struct reb_particle* const p = &r->particles[i];
        x[0] = p->x; x[1] = p->y; x[2] = p->z;
        a[0] = p->ax; a[1] = p->ay; a[2] = p->az;
    }else{
        for (int c=0; c<3; c++){
            x[c] = st->predictor_x[i][k][c];
            a[c] = st->predictor_a[i][k][c];
        }
    }
}

// Each body's bounds over the step: the box of its path between each two
// nodes (the chord's ends, widened by its sag, its radius if collisions are
// on and half exit_min_distance) and the sag.
static void contact_bounds(const struct reb_simulation* r, struct pfvi_state* st, size_t N, double h, int collide){
    const int s = st->options.stages;
    const double* const c = contact_nodes(st);
    double gap = 0.;
    for (int k=1; k<s; k++){
        gap = fmax(gap, c[k] - c[k-1]);
    }
    const double sag = PFVI_CONTACT_BOUND_SAFETY*(gap*h)*(gap*h)/8.;
    const double half_limit = 0.5*r->exit_min_distance;
    for (size_t i=0; i<N; i++){
        struct pfvi_contact_body* const b = &st->contact_bodies[i];
        double x[PFVI_STAGES_MAX][3], a2 = 0.;
        for (int k=0; k<s; k++){
            double a[3];
            contact_node(r, st, i, k, x[k], a);
            a2 = fmax(a2, a[0]*a[0] + a[1]*a[1] + a[2]*a[2]);
        }
        b->sag = sag*sqrt(a2);
        double pad = b->sag + (collide ? fmax(st->start[i].r, 0.) : 0.) + half_limit;
        pad = (pad == pad) ? pad : INFINITY;
        for (int k=0; k+1<s; k++){
            for (int d=0; d<3; d++){
                b->lo[k][d] = fmin(x[k][d], x[k+1][d]) - pad;
                b->hi[k][d] = fmax(x[k][d], x[k+1][d]) + pad;
                if (!(b->lo[k][d] == b->lo[k][d]) || !(b->hi[k][d] == b->hi[k][d])){
                    b->lo[k][d] = -INFINITY;
                    b->hi[k][d] = INFINITY;
                }
            }
        }
    }
}

// A lower bound on the pair's separation over the step: the closest its
// relative chords between nodes come to 0, less both bodies' sag.
static double contact_pair_bound(const struct reb_simulation* r, const struct pfvi_state* st, size_t i, size_t j){
    const int s = st->options.stages;
    double closest2 = INFINITY, prev[3] = {0., 0., 0.};
    for (int k=0; k<s; k++){
        double xi[3], ai[3], xj[3], aj[3];
        contact_node(r, st, i, k, xi, ai);
        contact_node(r, st, j, k, xj, aj);
        const double d[3] = {xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]};
        if (k > 0){
            // distance from 0 to the segment prev -> d
            const double e[3] = {d[0] - prev[0], d[1] - prev[1], d[2] - prev[2]};
            const double ee = e[0]*e[0] + e[1]*e[1] + e[2]*e[2];
            double u = (ee > 0.) ? -(prev[0]*e[0] + prev[1]*e[1] + prev[2]*e[2])/ee : 0.;
            u = fmin(1., fmax(0., u));
            const double c[3] = {prev[0] + u*e[0], prev[1] + u*e[1], prev[2] + u*e[2]};
            closest2 = fmin(closest2, c[0]*c[0] + c[1]*c[1] + c[2]*c[2]);
        }
        prev[0] = d[0]; prev[1] = d[1]; prev[2] = d[2];
    }
    return sqrt(closest2) - st->contact_bodies[i].sag - st->contact_bodies[j].sag;
}

// A pair's relative path: Chebyshev coefficients coef[c][n] (n < 2s + 2).
static void contact_path(const struct reb_simulation* r, const struct pfvi_state* st, size_t i, size_t j, double h,
        double coef[3][2*PFVI_STAGES_MAX+2]){
    const int s = st->options.stages, m = 2*s + 1;
    double data[2*PFVI_STAGES_MAX+2][3];
    for (int k=0; k<s; k++){
        double xi[3], ai[3], xj[3], aj[3];
        contact_node(r, st, i, k, xi, ai);
        contact_node(r, st, j, k, xj, aj);
        for (int c=0; c<3; c++){
            data[k][c] = xi[c] - xj[c];
            data[s + k][c] = h*h*(ai[c] - aj[c]);
        }
    }
    const struct reb_particle *pi0 = &st->start[i], *pj0 = &st->start[j];
    const struct reb_particle *pi1 = &r->particles[i], *pj1 = &r->particles[j];
    data[2*s][0] = h*(pi0->vx - pj0->vx); data[2*s][1] = h*(pi0->vy - pj0->vy); data[2*s][2] = h*(pi0->vz - pj0->vz);
    data[2*s+1][0] = h*(pi1->vx - pj1->vx); data[2*s+1][1] = h*(pi1->vy - pj1->vy); data[2*s+1][2] = h*(pi1->vz - pj1->vz);
    for (int n=0; n<m; n++){
        for (int c=0; c<3; c++){
            double sum = 0.;
            for (int k=0; k<2*s+2; k++){
                sum += st->contact_inverse[n][k]*data[k][c];
            }
            coef[c][n] = sum;
        }
    }
}

// |d(tau)|^2 (Clenshaw).
static double contact_distance2(const double coef[3][2*PFVI_STAGES_MAX+2], int m, double tau){
    const double z = 2.*tau - 1.;
    double d2 = 0.;
    for (int c=0; c<3; c++){
        double b1 = 0., b2 = 0.;
        for (int n=m-1; n>=1; n--){
            const double b0 = 2.*z*b1 - b2 + coef[c][n];
            b2 = b1;
            b1 = b0;
        }
        const double v = z*b1 - b2 + coef[c][0];
        d2 += v*v;
    }
    return d2;
}

// The first tau in [lo, hi] with |d|^2 < limit2, given f(lo) >= limit2 > f(hi).
static double contact_bisect(const double coef[3][2*PFVI_STAGES_MAX+2], int m, double lo, double hi, double limit2){
    for (int it=0; it<80 && hi - lo > 1e-16; it++){
        const double mid = 0.5*(lo + hi);
        if (contact_distance2(coef, m, mid) < limit2){
            hi = mid;
        }else{
            lo = mid;
        }
    }
    return hi;
}

// The smallest |d|^2 on [lo, hi] near a sampled minimum (golden section).
static double contact_minimum(const double coef[3][2*PFVI_STAGES_MAX+2], int m, double lo, double hi, double* at){
    const double g = 0.5*(sqrt(5.) - 1.);
    double a = lo, b = hi;
    double x1 = b - g*(b - a), x2 = a + g*(b - a);
    double f1 = contact_distance2(coef, m, x1), f2 = contact_distance2(coef, m, x2);
    for (int it=0; it<60 && b - a > 1e-15; it++){
        if (f1 < f2){
            b = x2; x2 = x1; f2 = f1;
            x1 = b - g*(b - a); f1 = contact_distance2(coef, m, x1);
        }else{
            a = x1; x1 = x2; f1 = f2;
            x2 = a + g*(b - a); f2 = contact_distance2(coef, m, x2);
        }
    }
    *at = (f1 < f2) ? x1 : x2;
    return fmin(f1, f2);
}

// The first tau in (0, 1] at which the pair's path is PFVI_CONTACT_DEPTH
// (at most half the dip) inside `limit`, starting outside it; 2 if none.
static double contact_first(const double coef[3][2*PFVI_STAGES_MAX+2], int m, double limit){
    const double limit2 = limit*limit;
    double f_prev = contact_distance2(coef, m, 0.);
    if (!(f_prev >= limit2)){
        return 2.;  // inside at the start (or not a number): REBOUND's own check
    }
    double f_prev2 = INFINITY;
    for (int p=1; p<=PFVI_CONTACT_SAMPLES; p++){
        const double tau = (double)p/PFVI_CONTACT_SAMPLES;
        const double f = contact_distance2(coef, m, tau);
        double bottom = NAN, lo = 0., hi = 0.;
        if (f < limit2){
            // Inside at this sample: end no later than the dip's bottom, so
            // that the pair is still approaching there.
            double at;
            lo = (p - 1.)/PFVI_CONTACT_SAMPLES;
            const double f_min = contact_minimum(coef, m, lo, tau, &at);
            bottom = f;
            hi = tau;
            if (f_min < f){
                bottom = f_min;
                hi = at;
            }
        }else if (f_prev <= f_prev2 && f_prev <= f){
            // A sampled minimum at the last sample (or at the start, rising
            // from there): the dip may go below between samples.
            double at;
            lo = (p >= 2) ? (p - 2.)/PFVI_CONTACT_SAMPLES : 0.;
            const double f_min = contact_minimum(coef, m, lo, tau, &at);
            if (f_min < limit2){
                bottom = f_min;
                hi = at;
            }
        }
        if (bottom == bottom){
            const double depth = fmin(PFVI_CONTACT_DEPTH*limit, 0.5*(limit - sqrt(bottom)));
            const double target = limit - depth;
            // f(lo) >= limit2 > target^2 >= ... f(hi) (bottom at hi: at most target^2).
            if (contact_distance2(coef, m, hi) >= target*target){
                return hi;
            }
            return contact_bisect(coef, m, lo, hi, target*target);
        }
        f_prev2 = f_prev;
        f_prev = f;
    }
    return 2.;
}

// Heapsort of order[0 .. n) by the boxes' low x at interval k: in place
// (glibc's qsort may allocate a buffer per call).
static double low_x(const struct pfvi_contact_body* b, const size_t* order, size_t i, int k){
    return b[order[i]].lo[k][0];
}

static void sift_down(const struct pfvi_contact_body* b, size_t* order, size_t root, size_t n, int k){
    for (;;){
        size_t child = 2*root + 1;
        if (child >= n){
            return;
        }
        if (child + 1 < n && low_x(b, order, child, k) < low_x(b, order, child + 1, k)){
            child++;
        }
        if (!(low_x(b, order, root, k) < low_x(b, order, child, k))){
            return;
        }
        const size_t tmp = order[root]; order[root] = order[child]; order[child] = tmp;
        root = child;
    }
}

static void order_by_low_x(const struct pfvi_contact_body* b, size_t* order, size_t n, int k){
    for (size_t i=n/2; i-- > 0;){
        sift_down(b, order, i, n, k);
    }
    for (size_t end=n; end-- > 1;){
        const size_t tmp = order[0]; order[0] = order[end]; order[end] = tmp;
        sift_down(b, order, 0, end, k);
    }
}

static int boxes_overlap(const struct pfvi_contact_body* p, const struct pfvi_contact_body* q, int k){
    return p->lo[k][0] <= q->hi[k][0] && q->lo[k][0] <= p->hi[k][0] && p->lo[k][1] <= q->hi[k][1]
        && q->lo[k][1] <= p->hi[k][1] && p->lo[k][2] <= q->hi[k][2] && q->lo[k][2] <= p->hi[k][2];
}

// The earliest tau in (0, 1] of a contact in the step just taken (2: none).
// Candidates: pairs whose boxes overlap between the same two nodes (swept
// along x, interval by interval: O(s N log N) plus the overlaps), then the
// chords' bound; the path is searched for those left.
static double contact_search(const struct reb_simulation* r, struct pfvi_state* st, size_t N, double h){
    const int collide = (r->collision != REB_COLLISION_NONE);
    const double limit = r->exit_min_distance > 0. ? r->exit_min_distance : 0.;
    const int s = st->options.stages, m = 2*s + 1;
    contact_bounds(r, st, N, h, collide);
    size_t* const order = st->contact_order;
    const struct pfvi_contact_body* const b = st->contact_bodies;
    double first = 2.;
    for (int k=0; k+1<s; k++){
        for (size_t i=0; i<N; i++){
            order[i] = i;
        }
        order_by_low_x(b, order, N, k);
        for (size_t oi=0; oi<N; oi++){
            const size_t i = order[oi];
            for (size_t oj=oi+1; oj<N; oj++){
                const size_t j = order[oj];
                if (!(b[j].lo[k][0] <= b[i].hi[k][0])){
                    break;
                }
                if (!boxes_overlap(&b[i], &b[j], k)){
                    continue;
                }
                int seen = 0;
                for (int l=0; l<k && !seen; l++){
                    seen = boxes_overlap(&b[i], &b[j], l);
                }
                if (seen){
                    continue;  // searched at an earlier interval
                }
                const double radii = collide ? fmax(st->start[i].r, 0.) + fmax(st->start[j].r, 0.) : 0.;
                if (!(radii > 0.) && !(limit > 0.)){
                    continue;
                }
                if (contact_pair_bound(r, st, i, j) > fmax(radii, limit)){
                    continue;
                }
                double coef[3][2*PFVI_STAGES_MAX+2];
                contact_path(r, st, i, j, h, coef);
                if (radii > 0.){
                    first = fmin(first, contact_first(coef, m, radii));
                }
                if (limit > 0.){
                    first = fmin(first, contact_first(coef, m, limit));
                }
            }
        }
    }
    return first;
}

// The controller's state and the stages' buffers as the step found them.
struct contact_snapshot {
    double dt, dt_reversible, rho, rho_sign, dt_proposed, track_done, track_kappa, density_scale, dt_last_full;
    double track_mismatch, t_compensation, t_compensated, density_sigma, density_dlog, predictor_h, predictor_t;
    int track_at_end, density_stages, predictor_stages, track_restarted;
    struct pfvi_steady steady;
    size_t density_N, predictor_N, var_predictor_N;
    double (*stage_a)[PFVI_STAGES_MAX][3];
    double (*predictor_a)[PFVI_STAGES_MAX][3];
    double (*stage_x)[PFVI_STAGES_MAX][3];
    double (*predictor_x)[PFVI_STAGES_MAX][3];
    double (*var_stage_a)[PFVI_STAGES_MAX][3];
    double (*var_predictor_a)[PFVI_STAGES_MAX][3];
    double (*var_stage_x)[PFVI_STAGES_MAX][3];
    double (*var_predictor_x)[PFVI_STAGES_MAX][3];
};

static struct contact_snapshot snapshot_of(const struct reb_simulation* r, const struct pfvi_state* st){
    return (struct contact_snapshot){
        .dt = r->dt, .dt_reversible = st->dt_reversible, .rho = st->rho, .rho_sign = st->rho_sign,
        .dt_proposed = st->dt_proposed, .track_done = st->track_done, .track_kappa = st->track_kappa,
        .density_scale = st->density_scale, .dt_last_full = st->dt_last_full, .track_mismatch = st->track_mismatch,
        .t_compensation = st->t_compensation, .t_compensated = st->t_compensated,
        .density_sigma = st->density_sigma, .density_dlog = st->density_dlog, .predictor_h = st->predictor_h,
        .predictor_t = st->predictor_t, .track_at_end = st->track_at_end, .track_restarted = st->track_restarted, .steady = st->steady,
        .density_stages = st->density_stages,
        .predictor_stages = st->predictor_stages, .density_N = st->density_N, .predictor_N = st->predictor_N,
        .var_predictor_N = st->var_predictor_N,
        .stage_a = st->stage_a, .predictor_a = st->predictor_a, .stage_x = st->stage_x, .predictor_x = st->predictor_x,
        .var_stage_a = st->var_stage_a, .var_predictor_a = st->var_predictor_a, .var_stage_x = st->var_stage_x,
        .var_predictor_x = st->var_predictor_x,
    };
}

static void snapshot_restore(struct reb_simulation* r, struct pfvi_state* st, const struct contact_snapshot* k){
    r->dt = k->dt;
    st->dt_reversible = k->dt_reversible; st->rho = k->rho; st->rho_sign = k->rho_sign;
    st->dt_proposed = k->dt_proposed; st->track_done = k->track_done; st->track_kappa = k->track_kappa;
    st->density_scale = k->density_scale; st->dt_last_full = k->dt_last_full; st->track_mismatch = k->track_mismatch;
    st->t_compensation = k->t_compensation; st->t_compensated = k->t_compensated;
    st->density_sigma = k->density_sigma; st->density_dlog = k->density_dlog; st->predictor_h = k->predictor_h;
    st->predictor_t = k->predictor_t; st->track_at_end = k->track_at_end; st->track_restarted = k->track_restarted; st->steady = k->steady;
    st->density_stages = k->density_stages;
    st->predictor_stages = k->predictor_stages; st->density_N = k->density_N; st->predictor_N = k->predictor_N;
    st->var_predictor_N = k->var_predictor_N;
    st->stage_a = k->stage_a; st->predictor_a = k->predictor_a; st->stage_x = k->stage_x;
    st->predictor_x = k->predictor_x; st->var_stage_a = k->var_stage_a; st->var_predictor_a = k->var_predictor_a;
    st->var_stage_x = k->var_stage_x; st->var_predictor_x = k->var_predictor_x;
    st->retry_valid = 0;
    st->var_retry_valid = 0;
}

int pfvi_contact_line(const struct reb_simulation* r){
    return r->collision == REB_COLLISION_LINE || r->collision == REB_COLLISION_LINETREE;
}

// Whether REBOUND's 'line'/'linetree' search at this step's end, over dt_last_done = dt,
// would find a pair that does not overlap at the end: its straight segments
// (each pair's end separation drawn back along its end relative velocity, as
// REBOUND's collision.c draws them, the inner ring of ghost boxes included)
// come within the sum of the radii where the step's path, searched by
// contact_search, does not.
static int contact_line_only(struct reb_simulation* r, size_t N, double dt){
    const struct reb_particle* const ps = r->particles;
    const int gx = r->N_ghost_x > 1 ? 1 : r->N_ghost_x;
    const int gy = r->N_ghost_y > 1 ? 1 : r->N_ghost_y;
    const int gz = r->N_ghost_z > 1 ? 1 : r->N_ghost_z;
    for (int bx=-gx; bx<=gx; bx++){
        for (int by=-gy; by<=gy; by++){
            for (int bz=-gz; bz<=gz; bz++){
                const struct reb_vec6d g = (bx || by || bz) ? reb_boundary_get_ghostbox(r, bx, by, bz)
                    : (struct reb_vec6d){0., 0., 0., 0., 0., 0.};
                for (size_t i=0; i<N; i++){
                    for (size_t j=0; j<N; j++){
                        const double rsum = ps[i].r + ps[j].r;
                        if (i == j || !(rsum > 0.)){
                            continue;
                        }
                        const double dx1 = ps[i].x + g.x - ps[j].x, dy1 = ps[i].y + g.y - ps[j].y,
                            dz1 = ps[i].z + g.z - ps[j].z;
                        const double r1 = dx1*dx1 + dy1*dy1 + dz1*dz1;
                        if (r1 <= rsum*rsum){
                            continue;  // a contact at the end: the path's own
                        }
                        const double dvx = ps[i].vx + g.vx - ps[j].vx, dvy = ps[i].vy + g.vy - ps[j].vy,
                            dvz = ps[i].vz + g.vz - ps[j].vz;
                        const double dx2 = dx1 - dt*dvx, dy2 = dy1 - dt*dvy, dz2 = dz1 - dt*dvz;
                        double rmin2 = fmin(r1, dx2*dx2 + dy2*dy2 + dz2*dz2);
                        const double tc = (dx1*dvx + dy1*dvy + dz1*dvz)/(dvx*dvx + dvy*dvy + dvz*dvz);
                        if (tc/dt >= 0. && tc/dt <= 1.){
                            const double dx3 = dx1 - tc*dvx, dy3 = dy1 - tc*dvy, dz3 = dz1 - tc*dvz;
                            rmin2 = fmin(rmin2, dx3*dx3 + dy3*dy3 + dz3*dz3);
                        }
                        if (rmin2 <= rsum*rsum){
                            return 1;
                        }
                    }
                }
            }
        }
    }
    return 0;
}

static double contact_step_once(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0,
        double (*take)(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0),
        const struct contact_snapshot* before_p);

double pfvi_contact_step(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0,
        double (*take)(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0)){
    if (!pfvi_contact_scratch(st, N)){
        return 0.;
    }
    const struct contact_snapshot before = snapshot_of(r, st);
    memcpy(st->contact_compensation, st->compensation, N*sizeof(*st->compensation));
    double h = contact_step_once(r, st, N, t0, take, &before);
    if (h == 0. || r->t == t0 || !pfvi_contact_line(r) || r->collision == REB_COLLISION_NONE){
        return h;
    }
    // 'line'/'linetree': the segments REBOUND draws back over this step must
    // meet only where its path does (dt_last_done is h after a step; the glue
    // reports 0 where it shows an output, so REBOUND looks at that state only).
    for (int k=0; contact_line_only(r, N, h); k++){
        if (k == PFVI_CONTACT_LINE_HALVINGS || t0 + 0.5*h == t0){
            st->statistics.n_contact_kept++;
            return h;
        }
        const double proposed = r->dt;
        pfvi_roll_back(r, st, N, t0);
        snapshot_restore(r, st, &before);
        memcpy(st->compensation, st->contact_compensation, N*sizeof(*st->compensation));
        r->dt = 0.5*h;
        const int uncapped = st->output_uncapped;
        st->output_uncapped = 0;
        const double h_half = take(r, st, N, t0);
        st->output_uncapped = uncapped;
        if (h_half == 0.){
            return 0.;
        }
        st->statistics.n_contact_steps++;
        st->statistics.n_rejected++;
        st->statistics.n_asymmetric++;
        if (st->options.epsilon == 0.){
            r->dt = before.dt;
        }else if (st->options.step_control != PFVI_STEP_CONTROL_SYMMETRIC){
            r->dt = proposed;
        }
        h = h_half;
    }
    return h;
}

static double contact_step_once(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0,
        double (*take)(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0),
        const struct contact_snapshot* before_p){
    const struct contact_snapshot before = *before_p;
    const double h = take(r, st, N, t0);
    if (h == 0. || r->t == t0){
        return h;
    }
    if (!contact_prepare(st)){
        return h;  // (not reached: the conditions are regular at s = 2 ... 8)
    }
    const double tau = contact_search(r, st, N, h);
    if (!(tau < 1.)){
        st->contact_chain = 0;
        return h;
    }
    const double cap = tau*h;
    if (t0 + cap == t0 || cap == h){
        return h;
    }
    if (st->contact_chain >= PFVI_CONTACT_RETAKES){
        st->statistics.n_contact_kept++;
        return h;
    }
    const double proposed = r->dt;  // the full step's proposal
    pfvi_roll_back(r, st, N, t0);
    snapshot_restore(r, st, &before);
    memcpy(st->compensation, st->contact_compensation, N*sizeof(*st->compensation));
    r->dt = cap;
    // (The retake ends at the contact even where the step would take its
    // whole interval past an output: the output is shown from its end.)
    const int uncapped = st->output_uncapped;
    st->output_uncapped = 0;
    const double h_contact = take(r, st, N, t0);
    st->output_uncapped = uncapped;
    if (h_contact == 0.){
        return 0.;
    }
    st->contact_chain++;
    st->statistics.n_contact_steps++;
    st->statistics.n_rejected++;
    st->statistics.n_asymmetric++;
    if (st->options.epsilon == 0.){
        r->dt = before.dt;  // fixed steps go on at sim.dt
    }else if (st->options.step_control != PFVI_STEP_CONTROL_SYMMETRIC){
        r->dt = proposed;   // the accept/reject controls go on from the full step's proposal
    }
    return h_contact;
}
