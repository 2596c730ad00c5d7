"""Collisions and close encounters inside pfvi's steps (issue 35; docs/collisions.md).

    python -P benchmarks/collisions.py --parts graze,time,exit --output docs/collisions-tables.md
    python -P benchmarks/collisions.py --parts ensemble --seeds 20     # a few minutes
    python -P benchmarks/collisions.py --parts cost                    # N = 100 and 2000 with radii

graze:    two bodies (G M = 1, radii 0.006 and 0.004: sum R = 0.01), pericentre q = x R,
          bound (e = 0.9, from apocentre) and hyperbolic (e = 1.5, 5, 50: v_inf = 0.7,
          2, 7 times the escape speed at R), "direct" and "line", merge: a merger is
          right iff q < R. pfvi (defaults), IAS15 (default epsilon), BS (default).
time:     the same encounters halted at contact ("halt"): sim.t against the Kepler
          time of r = R (two bodies: exact), in units of R/v (v at contact).
exit:     no radii, exit_min_distance = q (1 +- 1e-6): an Encounter iff q < limit,
          and the time against the Kepler time of r = limit.
ensemble: 10 bodies (a star, 9 planets of 1e-4 ... 1e-3 with inflated radii, packed
          at 2.5 mutual Hill radii), 1000 time units, merge: mergers and the first
          merger (time and pair) for pfvi, IAS15 at its default and at epsilon 1e-12.
cost:     wall time per step with radii and "direct" against "none", N = 100 and 2000.
"""
import argparse
import math
import sys
import time

import numpy as np
import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")

R_SUM = 0.01
XS = (0.5, 0.9, 0.99, 0.999, 0.9999, 1.0001, 1.001, 1.01, 1.1)
ES = (0.9, 1.5, 5.0, 50.0)


def encounter(x, e, integrator, collision="direct", resolve="merge", radii=True):
    """Two bodies approaching a pericentre q = x R_SUM; returns (sim, t_peri)."""
    sim = rebound.Simulation()
    sim.add(m=1.0, r=0.6 * R_SUM if radii else 0.)
    q = x * R_SUM
    a = q / (1 - e)
    if e < 1:
        f0 = -math.pi * 0.999
    else:
        # from 30 q (or 0.9 of the asymptote's angle)
        cosf = (a * (1 - e * e) / (30 * q) - 1) / e
        f0 = -min(0.9 * math.acos(-1 / e), math.acos(max(-1., min(1., cosf))))
    sim.add(m=1e-3, r=0.4 * R_SUM if radii else 0., a=a, e=e, f=f0, primary=sim.particles[0])
    sim.move_to_com()
    set_integrator(sim, integrator)
    sim.collision = collision
    sim.collision_resolve = resolve
    return sim


def set_integrator(sim, integrator):
    name, _, eps = integrator.partition(":")
    sim.integrator = name
    if eps:
        if name in ("pfvi", "ias15"):
            sim.integrator.epsilon = float(eps)
        elif name == "bs":
            sim.integrator.eps_rel = sim.integrator.eps_abs = float(eps)


def kepler_time_to(sim, radius):
    """Time from now to the first r = radius on the relative two-body orbit (inf if never)."""
    o = sim.particles[1].orbit(primary=sim.particles[0])
    p = o.a * (1 - o.e * o.e)
    cosf = (p / radius - 1) / o.e
    if cosf > 1 + 1e-9:
        return math.inf
    fc = -math.acos(max(-1., cosf))
    return mean_anomaly(o.e, fc) / abs(o.n) - mean_anomaly(o.e, math.remainder(o.f, 2 * math.pi)) / abs(o.n)


def t_peri(sim):
    """Time from now to the pericentre of the relative orbit."""
    o = sim.particles[1].orbit(primary=sim.particles[0])
    return -mean_anomaly(o.e, math.remainder(o.f, 2 * math.pi)) / abs(o.n)


def mean_anomaly(e, f):
    if e < 1:
        E = 2 * math.atan(math.sqrt((1 - e) / (1 + e)) * math.tan(f / 2))
        return E - e * math.sin(E)
    F = 2 * math.atanh(math.sqrt((e - 1) / (e + 1)) * math.tan(f / 2))
    return e * math.sinh(F) - F


def graze(integrators=("pfvi", "ias15", "bs")):
    rows = []
    for e in ES:
        for coll in ("direct", "line"):
            for x in XS:
                row = {"e": e, "collision": coll, "x": x}
                for name in integrators:
                    sim = encounter(x, e, name, coll)
                    sim.integrate(2 * t_peri(sim))
                    row[name] = sim.N == 1
                rows.append(row)
    return rows


def contact_time(integrators=("pfvi", "ias15", "ias15:1e-12", "bs")):
    rows = []
    for e in ES:
        for x in (0.5, 0.9, 0.99, 0.999):
            row = {"e": e, "x": x}
            sim = encounter(x, e, "ias15", "direct", "halt")
            t_true = kepler_time_to(sim, R_SUM)
            o = sim.particles[1].orbit(primary=sim.particles[0])
            v = math.sqrt(1.001 * (2 / R_SUM - 1 / o.a))
            for name in integrators:
                sim = encounter(x, e, name, "direct", "halt")
                try:
                    sim.integrate(2 * t_peri(sim))
                    row[name] = math.nan
                except rebound.Collision:
                    row[name] = (sim.t - t_true) * v / R_SUM
            rows.append(row)
    return rows


def exit_scan(integrators=("pfvi", "ias15", "bs")):
    rows = []
    for e in ES:
        for x in (0.5, 0.999, 1.0):
            for rel in (1 + 1e-6, 1 - 1e-6):
                q = x * R_SUM
                limit = q * rel
                row = {"e": e, "q": q, "limit/q": rel}
                for name in integrators:
                    sim = encounter(x, e, name, "none", radii=False)
                    sim.exit_min_distance = limit
                    t_true = kepler_time_to(sim, limit)
                    try:
                        sim.integrate(2 * t_peri(sim))
                        row[name] = None
                    except rebound.Encounter:
                        row[name] = (sim.t - t_true) / t_true if t_true < math.inf else math.inf
                rows.append(row)
    return rows


def scattering_sim(seed, integrator):
    rng = np.random.default_rng(seed)
    sim = rebound.Simulation()
    sim.add(m=1.0, r=0.005, name="star")
    a = 1.0
    for k in range(9):
        m = 10 ** rng.uniform(-4, -3)
        sim.add(m=m, r=0.01 * (m / 1e-3) ** (1 / 3) * 3, a=a, e=rng.uniform(0, 0.05),
                inc=rng.uniform(0, 0.02), Omega=rng.uniform(0, 2 * math.pi),
                omega=rng.uniform(0, 2 * math.pi), f=rng.uniform(0, 2 * math.pi), name=f"p{k + 1}")
        a *= 1 + 2.5 * (2 * 1e-3 / 3) ** (1 / 3)
    sim.move_to_com()
    set_integrator(sim, integrator)
    sim.collision = "direct"
    return sim


def scattering(seed, integrator, t_end=1000.):
    sim = scattering_sim(seed, integrator)
    first = []

    def resolve(sim_pointer, collision):
        # REBOUND's merge, in Python: the lower index keeps the merged body.
        s = sim_pointer.contents
        ps = s.particles
        i, j = sorted((collision.p1, collision.p2))
        pi, pj = ps[i], ps[j]
        if not first:
            first.append((s.t, tuple(sorted((pi.name, pj.name)))))
        m = pi.m + pj.m
        for f in ("x", "y", "z", "vx", "vy", "vz"):
            setattr(pi, f, (pi.m * getattr(pi, f) + pj.m * getattr(pj, f)) / m)
        pi.r = (pi.r ** 3 + pj.r ** 3) ** (1 / 3)
        pi.m = m
        return 2 if collision.p2 == j else 1  # remove the other one

    sim.collision_resolve = resolve
    n0 = sim.N
    wall = time.perf_counter()
    sim.integrate(t_end)
    wall = time.perf_counter() - wall
    t_first, pair = first[0] if first else (math.nan, None)
    return {"mergers": n0 - sim.N, "t_first": t_first, "pair": pair, "wall": wall,
            "steps": sim.steps_done, "contact_steps": sim.integrator.n_contact_steps if integrator.startswith("pfvi") else 0}


def first_contact_reference(seed, samples=2000):
    """The first merger's time by IAS15 at epsilon 1e-12 with a contact search along its
    steps: halted at the first step end in contact, the step is taken again from its
    start in `samples` equal parts (exact finish at each), halted at the first inside."""
    sim = scattering_sim(seed, "ias15:1e-12")
    sim.collision_resolve = "halt"
    try:
        sim.integrate(1000.)
        return math.nan
    except rebound.Collision:
        pass
    t_hit, h = sim.t, sim.dt_last_done
    sim = scattering_sim(seed, "ias15:1e-12")
    sim.collision_resolve = "halt"
    sim.integrate(t_hit - h)
    try:
        for k in range(1, samples + 1):
            sim.integrate(t_hit - h + k * h / samples)
    except rebound.Collision:
        return sim.t
    return t_hit


def ensemble(seeds, integrators=("pfvi", "ias15", "ias15:1e-12")):
    out = {}
    for name in integrators:
        out[name] = [scattering(seed, name) for seed in range(seeds)]
        print(name, "mergers", sum(r["mergers"] for r in out[name]),
              "wall %.1f s" % sum(r["wall"] for r in out[name]), file=sys.stderr)
    return out


def disk(N, radius, seed=1):
    """A star and N - 1 planetesimals (m = 1e-9) on a in [1, 2], e, i <= 0.05."""
    rng = np.random.default_rng(seed)
    sim = rebound.Simulation()
    sim.add(m=1.0, r=radius)
    for _ in range(N - 1):
        sim.add(m=1e-9, r=radius, a=rng.uniform(1, 2), e=rng.uniform(0, 0.05), inc=rng.uniform(0, 0.05),
                Omega=rng.uniform(0, 2 * math.pi), omega=rng.uniform(0, 2 * math.pi), f=rng.uniform(0, 2 * math.pi))
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.collision = "direct"
    return sim


def cost(sizes=((100, 200), (2000, 3))):
    """Wall time per step with radii against all radii 0 ("direct" both: REBOUND's own search
    runs in both, pfvi's contact search only with radii), same steps (no contact)."""
    print("## Cost of the contact search (\"direct\", no contact made)\n")
    print("| N | steps | s/step, radii 0 | s/step, radii 1e-4 | contact search | |")
    print("|---|---|---|---|---|---|")
    for N, steps in sizes:
        best = {0.: math.inf, 1e-4: math.inf}
        counts = {}
        # alternated, best of each: the machine's load varies from run to run
        for _ in range(10 if N < 1000 else 3):
            for radius in best:
                sim = disk(N, radius)
                sim.steps(1)
                t = time.perf_counter()
                sim.steps(steps)
                best[radius] = min(best[radius], (time.perf_counter() - t) / steps)
                counts[radius] = sim.integrator.n_contact_steps
        a, b = best[0.], best[1e-4]
        print(f"| {N} | {steps} | {a:.3g} | {b:.3g} | {100 * (b / a - 1):+.1f}% | contact steps {counts[1e-4]} |")
    print()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--parts", default="graze,time,exit")
    ap.add_argument("--seeds", type=int, default=20)
    args = ap.parse_args(argv)
    parts = args.parts.split(",")
    if "graze" in parts:
        rows = graze()
        print("## Grazing encounters: merger (M) or not (-); right iff M exactly where x < 1\n")
        print("| e | search | " + " | ".join(f"x = {x}" for x in XS) + " |")
        print("|---|---|" + "---|" * len(XS))
        wrong = {}
        for e in ES:
            for coll in ("direct", "line"):
                cells = []
                for x in XS:
                    r = [r for r in rows if r["e"] == e and r["collision"] == coll and r["x"] == x][0]
                    cells.append(" ".join(("M" if r[n] else "-") + n[0] for n in ("pfvi", "ias15", "bs")))
                    for n in ("pfvi", "ias15", "bs"):
                        wrong[n] = wrong.get(n, 0) + (r[n] != (x < 1))
                print(f"| {e} | {coll} | " + " | ".join(cells) + " |")
        print(f"\nwrong of {len(rows)}: " + ", ".join(f"{n} {w}" for n, w in wrong.items()) + "\n")
        sys.stdout.flush()
    if "time" in parts:
        rows = contact_time()
        print("## Contact time (halt) minus the Kepler time of r = R, in units of R/v\n")
        names = ("pfvi", "ias15", "ias15:1e-12", "bs")
        print("| e | x | " + " | ".join(names) + " |")
        print("|---|---|" + "---|" * len(names))
        for r in rows:
            print(f"| {r['e']} | {r['x']} | " + " | ".join(f"{r[n]:.2g}" for n in names) + " |")
        print()
        sys.stdout.flush()
    if "ensemble" in parts:
        res = ensemble(args.seeds)
        names = list(res)
        ref = names[-1]
        print(f"## Scattering ensemble: {args.seeds} seeds, 10 bodies, t = 1000, merge (a Python resolve)\n")
        print("| seed | " + " | ".join(f"{n}: mergers, first (t, pair)" for n in names) + " |")
        print("|---|" + "---|" * len(names))
        for k in range(args.seeds):
            print(f"| {k} | " + " | ".join(
                f"{res[n][k]['mergers']}, {res[n][k]['t_first']:.6g} {res[n][k]['pair']}" for n in names) + " |")
        print()
        for n in names:
            m = [r["mergers"] for r in res[n]]
            print(f"{n}: mergers {sum(m)}, wall {sum(r['wall'] for r in res[n]):.1f} s, "
                  f"steps {sum(r['steps'] for r in res[n])}, contact steps {sum(r['contact_steps'] for r in res[n])}")
        refs = [first_contact_reference(k) for k in range(args.seeds)]
        print("first merger against IAS15 at 1e-12 with a contact search along its steps (2000 parts of the "
              "step that found it), relative time difference:")
        for n in names:
            rel = [abs(r["t_first"] - t) / t for r, t in zip(res[n], refs) if t == t]
            print(f"  {n}: median {np.median(rel):.2g}, max {max(rel):.2g} ({len(rel)} seeds)")
        for n in names[:-1]:
            d = np.array([r["mergers"] for r in res[n]]) - np.array([r["mergers"] for r in res[ref]])
            same = [(a["t_first"], b["t_first"]) for a, b in zip(res[n], res[ref]) if a["pair"] == b["pair"]]
            rel = [abs(a - b) / b for a, b in same if b == b]
            print(f"{n} - {ref}: per-seed merger difference mean {d.mean():+.2f} +- {d.std(ddof=1) / math.sqrt(len(d)):.2f} "
                  f"(sd {d.std(ddof=1):.2f}); same first pair in {len(same)}/{len(d)} seeds, first-merger time "
                  f"relative difference there: median {np.nanmedian(rel) if rel else math.nan:.2g}, max {max(rel) if rel else math.nan:.2g}")
        print()
    if "cost" in parts:
        cost()
    if "pages" in parts:
        pages()
    if "exit" in parts:
        rows = exit_scan()
        print("## exit_min_distance = q (1 +- 1e-6): Encounter raised (relative time error against the "
              "Kepler time of r = limit) or not (-)\n")
        print("| e | q | limit/q | pfvi | ias15 | bs |")
        print("|---|---|---|---|---|---|")
        wrong = {}
        for r in rows:
            cells = []
            for n in ("pfvi", "ias15", "bs"):
                cells.append("-" if r[n] is None else f"{r[n]:.1e}")
                wrong[n] = wrong.get(n, 0) + ((r[n] is not None) != (r["limit/q"] > 1))
            print(f"| {r['e']} | {r['q']:.4g} | {r['limit/q']:.7f} | " + " | ".join(cells) + " |")
        print(f"\nwrong of {len(rows)}: " + ", ".join(f"{n} {w}" for n, w in wrong.items()) + "\n")


if __name__ == "__main__":
    main()
