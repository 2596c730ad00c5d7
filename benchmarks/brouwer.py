"""Round-off over long runs (issue 25): does pfvi's error grow like a random
walk (Brouwer's law) beside IAS15 and WHFast? Writes a markdown report and a
PNG (docs/roundoff.md quotes them).

    python -P benchmarks/brouwer.py --orbits 1e4 --members 16 --output docs/roundoff-1e4.md
    python -P benchmarks/brouwer.py --orbits 1e6 --members 2 --output docs/roundoff-1e6.md

Scenes: Kepler e = 0.5 and e = 0.99 (m = 1e-3, COM frame, a = 1) and the
outer solar system (rebound_pfvi.scenes' outer-solar-system; its orbits are
Jupiter's). Integrators: pfvi at its defaults and at epsilon 1e-12, IAS15 at
its default, WHFast (dt = 1/50 of the period; on two bodies it is the
Kepler solver alone, with no kick, so its error is the solver's round-off;
on the outer solar system dt = 1/20 of Jupiter's period, a common choice).

Each member starts from initial conditions that differ far below what the
truncation feels (member k: a or Jupiter's x times 1 + k 2^-40; members one
ulp apart stay correlated for hundreds of orbits under the Newton stage
solve, which lands on the exact fixed point in doubles: docs/solve.md) and is sampled 200 times
(20 per tenth of the run) without shortening a step (exact_finish_time = 0).
Per setting the report gives:
- the RMS relative energy error over the first and the last tenth (over
  members and samples), and the slope of log RMS against log t over the ten
  tenths (Brouwer: 0.5; a bias: 1);
- the ensemble's mean relative energy error in standard errors (SE: the
  spread over sqrt(members)) at its largest over the 200 samples: unbiased
  round-off stays within about 2-3;
- on Kepler orbits, the along-track error: the mean longitude against the
  exact two-body motion (its mean motion computed from the initial doubles
  in 40-digit decimals), RMS over the last tenth and the slope (Brouwer:
  1.5);
- wall time per run and per step.
Runs go through rebound_pfvi.runner (worker processes; --workers).
"""
import argparse
import math
import sys
import time
from decimal import Decimal, getcontext

import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")
from rebound_pfvi import runner, scenes
from rebound_pfvi.integrators import configure

SAMPLES = 200
TENTHS = 10

SETTINGS = (
    ("pfvi", "pfvi defaults", ()),
    ("pfvi", "pfvi epsilon=1e-12", (("epsilon", 1e-12),)),
    ("ias15", "IAS15 defaults", ()),
    ("whfast", "WHFast", ()),
)
SCENES = ("kepler-e0.5", "kepler-e0.99", "outer-solar-system")


def build(scene, member):
    """The scene's simulation, member k's initial conditions 1 + k 2^-40 off."""
    bump = 1.0 + member * 2.0**-40
    if scene.startswith("kepler"):
        e = float(scene.split("-e")[1])
        sim = scenes.new_simulation()
        sim.G = 1.0
        sim.add(m=1.0)
        sim.add(m=1e-3, a=bump, e=e)
        sim.move_to_com()
        period = sim.particles[1].P
    else:
        sim = scenes.OuterSolarSystem().build()
        sim.particles[1].x *= bump
        period = sim.particles[1].P
    return sim, period


def mean_motion(sim):
    """The exact two-body mean motion of particle 1 about 0, from the doubles
    of the state (40 digits)."""
    getcontext().prec = 40
    p, q = sim.particles[0], sim.particles[1]
    d = [Decimal(q.x) - Decimal(p.x), Decimal(q.y) - Decimal(p.y), Decimal(q.z) - Decimal(p.z)]
    w = [Decimal(q.vx) - Decimal(p.vx), Decimal(q.vy) - Decimal(p.vy), Decimal(q.vz) - Decimal(p.vz)]
    mu = Decimal(sim.G) * (Decimal(p.m) + Decimal(q.m))
    r = (d[0]**2 + d[1]**2 + d[2]**2).sqrt()
    energy = (w[0]**2 + w[1]**2 + w[2]**2) / 2 - mu / r
    a = -mu / (2 * energy)
    return (mu / a**3).sqrt()


def one_run(scene, family, options, orbits, member):
    """One member: (energy errors, along-track errors or None, times, steps, seconds)."""
    sim, period = build(scene, member)
    dt = period / (50.0 if scene.startswith("kepler") else 20.0) if family == "whfast" else None
    configure(sim, family, dt, **dict(options))
    kepler = scene.startswith("kepler")
    if kepler:
        n = mean_motion(sim)
        l0 = Decimal(sim.particles[1].orbit(primary=sim.particles[0]).l)
    energy0 = sim.energy()
    t_end = orbits * period
    energies, along, times = [], [], []
    steps = 0
    start = time.perf_counter()
    for j in range(1, SAMPLES + 1):
        sim.integrate(t_end * j / SAMPLES, exact_finish_time=0)
        energies.append(sim.energy() / energy0 - 1.0)
        times.append(sim.t)
        if kepler:
            l = sim.particles[1].orbit(primary=sim.particles[0]).l
            exact = (l0 + n * Decimal(sim.t)) % Decimal(2 * math.pi)
            diff = (Decimal(l) - exact) % Decimal(2 * math.pi)
            diff = float(diff) if diff < Decimal(math.pi) else float(diff) - 2 * math.pi
            along.append(diff)
    seconds = time.perf_counter() - start
    steps = sim.steps_done
    return energies, (along if kepler else None), times, steps, seconds


def slope(xs, ys):
    """Least-squares slope of log y against log x (y > 0)."""
    points = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if y > 0]
    if len(points) < 2:
        return float("nan")
    mx = sum(p[0] for p in points) / len(points)
    my = sum(p[1] for p in points) / len(points)
    sxx = sum((p[0] - mx)**2 for p in points)
    return sum((p[0] - mx) * (p[1] - my) for p in points) / sxx


def tenth_rms(series):
    """RMS over members and the samples of each tenth: 10 values."""
    per = SAMPLES // TENTHS
    out = []
    for k in range(TENTHS):
        values = [v for s in series for v in s[k * per:(k + 1) * per]]
        out.append(math.sqrt(sum(v * v for v in values) / len(values)))
    return out


def ensemble_bias(series):
    """The largest |mean|/SE over the samples (members >= 2), and its sample."""
    m = len(series)
    if m < 2:
        return float("nan")
    worst = 0.0
    for j in range(SAMPLES):
        values = [s[j] for s in series]
        mean = sum(values) / m
        sd = math.sqrt(sum((v - mean)**2 for v in values) / (m - 1))
        if sd > 0:
            worst = max(worst, abs(mean) / (sd / math.sqrt(m)))
    return worst


def spread_rms(series):
    """The spread over members (standard deviation) at each sample, RMS per tenth."""
    m = len(series)
    if m < 2:
        return None
    per = SAMPLES // TENTHS
    spreads = []
    for j in range(SAMPLES):
        values = [s[j] for s in series]
        mean = sum(values) / m
        spreads.append(math.sqrt(sum((v - mean)**2 for v in values) / (m - 1)))
    return [math.sqrt(sum(v * v for v in spreads[k * per:(k + 1) * per]) / per) for k in range(TENTHS)]


def summarise(outcomes):
    energies = [o[0] for o in outcomes]
    along = [o[1] for o in outcomes if o[1] is not None]
    times = outcomes[0][2]
    per = SAMPLES // TENTHS
    mids = [sum(times[k * per:(k + 1) * per]) / per for k in range(TENTHS)]
    rms = tenth_rms(energies)
    row = {
        "first": rms[0], "last": rms[-1], "slope": slope(mids, rms), "rms": rms, "mids": mids,
        "bias": ensemble_bias(energies),
        "spread_slope": (slope(mids, spread_rms(energies)) if len(energies) > 1 else float("nan")),
        "seconds": sum(o[4] for o in outcomes) / len(outcomes),
        "per_step": sum(o[4] for o in outcomes) / sum(o[3] for o in outcomes),
        "energies": energies, "times": times,
    }
    if along:
        arms = tenth_rms(along)
        row.update({"along_last": arms[-1], "along_slope": slope(mids, arms), "along_rms": arms})
    return row


def plot(results, orbits, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(results), figsize=(5 * len(results), 8), squeeze=False)
    for col, scene in enumerate(results):
        ax = axes[0][col]
        for label, row in results[scene].items():
            ax.loglog(row["mids"], row["rms"], "o-", label=label)
        ref = results[scene].get("IAS15 defaults") or next(iter(results[scene].values()))
        t0, y0 = ref["mids"][0], ref["rms"][0]
        ts = [ref["mids"][0], ref["mids"][-1]]
        ax.loglog(ts, [y0 * (t / t0)**0.5 for t in ts], "k--", lw=0.8, label="t^1/2")
        ax.loglog(ts, [y0 * (t / t0) for t in ts], "k:", lw=0.8, label="t")
        ax.set_title(f"{scene}: RMS energy error per tenth")
        ax.set_xlabel("t (code units)")
        ax.legend(fontsize=7)
        ax = axes[1][col]
        plotted = False
        for label, row in results[scene].items():
            if "along_rms" in row:
                ax.loglog(row["mids"], row["along_rms"], "o-", label=label)
                plotted = True
        if plotted:
            ref = results[scene].get("IAS15 defaults")
            t0, y0 = ref["mids"][0], ref["along_rms"][0]
            ax.loglog(ts, [y0 * (t / t0)**1.5 for t in ts], "k--", lw=0.8, label="t^3/2")
            ax.set_title(f"{scene}: RMS along-track error (rad)")
            ax.legend(fontsize=7)
        else:
            ax.set_axis_off()
    fig.suptitle(f"{orbits:g} orbits, relative energy error and along-track error (benchmarks/brouwer.py)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def report(results, args, elapsed):
    exponent = math.log10(args.orbits)
    label = f"10^{exponent:.0f}" if exponent == round(exponent) else f"{args.orbits:g}"
    lines = [f"## {label} orbits, {args.members} member(s) per setting", "",
             f"`python -P benchmarks/brouwer.py --orbits {args.orbits_text} --members {args.members} "
             f"--output {args.output}`: {elapsed / 60:.0f} min on {args.workers} worker(s), "
             f"rebound {rebound.__version__}. RMS over members and the 20 samples of a tenth; "
             "slope of log RMS against log t over the ten tenths; spread slope: the same for the "
             "members' standard deviation (round-off alone, where the truncation error is the same in "
             "every member); bias = the ensemble mean's "
             "largest distance from zero over the 200 samples, in standard errors; along-track: "
             "mean longitude against the exact two-body motion.", "",
             "| scene | integrator | energy RMS, first tenth | last tenth | slope | spread slope | bias (SE) "
             "| along-track RMS, last tenth (rad) | slope | s/run | us/step |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for scene in results:
        for label, row in results[scene].items():
            along = (f"{row['along_last']:.1e} | {row['along_slope']:.2f}" if "along_last" in row else "- | -")
            bias = f"{row['bias']:.1f}" if row["bias"] == row["bias"] else "-"
            spread = f"{row['spread_slope']:.2f}" if row["spread_slope"] == row["spread_slope"] else "-"
            lines.append(f"| {scene} | {label} | {row['first']:.1e} | {row['last']:.1e} | {row['slope']:.2f} "
                         f"| {spread} | {bias} | {along} | {row['seconds']:.1f} | {1e6 * row['per_step']:.2f} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--orbits", default="1e4", help="orbits per run (as written, e.g. 1e6)")
    parser.add_argument("--members", type=int, default=16)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--output", default=None, help="markdown file (a PNG is written beside it)")
    parser.add_argument("--scenes", nargs="*", default=list(SCENES))
    args = parser.parse_args(argv)
    args.orbits_text, args.orbits = args.orbits, float(args.orbits)
    if args.output:
        open(args.output, "a").close()
    tasks, keys = [], []
    for scene in args.scenes:
        for family, label, options in SETTINGS:
            for member in range(args.members):
                tasks.append(runner.Task(one_run, (scene, family, options, args.orbits, member)))
                keys.append((scene, label))
    start = time.perf_counter()

    def done(index, outcome):
        print(f"{keys[index][0]} {keys[index][1]} member {tasks[index].args[-1]}: {outcome[0]}"
              + (f" {outcome[1][4]:.0f} s" if outcome[0] == "ok" else f" {outcome[1]}"), flush=True)

    outcomes = runner.run_tasks(tasks, workers=args.workers, done=done)
    elapsed = time.perf_counter() - start
    grouped = {}
    for key, outcome in zip(keys, outcomes):
        if outcome[0] != "ok":
            raise SystemExit(f"{key}: {outcome}")
        grouped.setdefault(key, []).append(outcome[1])
    results = {scene: {} for scene in args.scenes}
    for (scene, label), runs in grouped.items():
        results[scene][label] = summarise(runs)
    text = report(results, args, elapsed)
    print(text)
    if args.output:
        with open(args.output, "w") as f:
            f.write(text)
        plot(results, args.orbits, args.output.rsplit(".", 1)[0] + ".png")
    return results


if __name__ == "__main__":
    main()
