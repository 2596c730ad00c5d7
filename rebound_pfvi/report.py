"""Writing results: a sweep's JSON, CSV, markdown page and work-precision PNG, and the stability report.

Both read :class:`rebound_pfvi.runs.Run` s; a run's row in the JSON and CSV
files is its :meth:`~rebound_pfvi.runs.Run.to_dict`."""
from __future__ import annotations

import csv
import json
import math
import os
import platform
from typing import TYPE_CHECKING, Any, Dict, Iterable, List, Optional

from .checks import file_name

if TYPE_CHECKING:
    import pathlib

    from .compare import Results
    from .runs import Run
    from .stability import Report as StabilityReport

#: Position errors (AU) at which the summary names the fastest run of each line.
TARGETS = (1e-2, 1e-4, 1e-6, 1e-8, 1e-10)
COLUMNS = ("line", "knob", "value", "verdict", "verdict_detail", "status", "steps",
           "force_evaluations", "wall_s", "energy_error_max",
           "energy_error_final", "position_error", "relative_position_error", "attempts_per_step",
           "iterations_mean")


def fmt(value: Any, spec: str = ".2g") -> str:
    """A number for a table: "-" for None, inf and nan as they are."""
    if value is None:
        return "-"
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return format(value, spec)


def _knob(row: Run) -> str:
    if row.knob == "steps/period":
        return f"{row.value:g} steps/period"
    return f"{row.knob} {row.value:.0e}"


def length_unit(results: Results) -> str:
    """How the page names the position error's unit."""
    return str(getattr(results.scene, "length_unit", "AU"))


def markdown_table(rows: Iterable[Run], length: str = "AU") -> str:
    """Every run of a sweep as a markdown table, with its verdict, counts, times and errors."""
    lines = ["| integrator | setting | verdict | steps | force evals | wall [s] | max rel. energy err | "
             f"final rel. energy err | position err [{length}] | note |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r.status != "ok":
            message = r.verdict_detail or r.status
            lines.append(f"| {r.label} | {_knob(r)} | {r.verdict or '-'} | - | - | - | - | - | - | "
                         f"{message.replace('|', '/')} |")
            continue
        note = ""
        if r.verdict == "inaccurate":
            note = r.verdict_detail
        if r.warnings:
            note += ("; " if note else "") + "REBOUND warned (below)"
        if r.family == "pfvi" and r.pfvi is not None:
            note += ("; " if note else "") + (f"{r.pfvi['attempts_per_step']:.1f} trials/step, "
                                              f"{r.pfvi['iterations_mean']:.1f} iterations")
        lines.append(f"| {r.label} | {_knob(r)} | {r.verdict or '-'} | {r.steps} | "
                     f"{r.force_evaluations} | "
                     f"{_number(r.wall_s):.3g} | {_number(r.energy_error_max):.2e} | "
                     f"{_number(r.energy_error_final):.2e} | {_number(r.position_error):.2e} | {note} |")
    return "\n".join(lines)


def _number(value: Optional[float]) -> float:
    """A measurement a finished run has (its type says it may be missing: then nan)."""
    return math.nan if value is None else value


def fastest(rows: Iterable[Run], target: float) -> Dict[str, Run]:
    """For each line, the run with the least wall time whose position error is <= target."""
    best: Dict[str, Run] = {}
    for r in rows:
        wall = _number(r.wall_s)
        if not (math.isfinite(wall) and wall > 0.0):
            continue  # no usable time: it cannot be ranked
        if r.status == "ok" and _number(r.position_error) <= target:
            if r.label not in best or _number(r.wall_s) < _number(best[r.label].wall_s):
                best[r.label] = r
    return best


#: Two wall times within this ratio are a tie. Measured: the slowest over the
#: fastest best-of-3 time of one setting in three quick sweeps, one after
#: another on the 2-core development machine, has its 90th percentile at
#: 1.48 on the comet (the main job) and 1.57 on kepler e = 0.95
#: (`python3 -P benchmarks/noise.py [--scene kepler]`; docs/results.md, "Ties").
TIE_RATIO = 1.6


def tied(a: Run, b: Run) -> bool:
    """Whether b's wall time is within the run-to-run noise (TIE_RATIO) of a's."""
    low, high = sorted((_number(a.wall_s), _number(b.wall_s)))
    return high <= low * TIE_RATIO


def summary_table(rows: List[Run], floor: float = 0.0, length: str = "AU") -> str:
    """The fastest run of each line that reaches each position error, as a
    markdown table; the fastest, and every line tied with it (within
    TIE_RATIO), in bold."""
    lines_in_order = list(dict.fromkeys(r.label for r in rows))
    targets = [t for t in TARGETS if t > floor]
    head = "| position error <= | " + " | ".join(lines_in_order) + " |"
    lines = [head, "|---|" + "---|" * len(lines_in_order)]
    for target in targets:
        best = fastest(rows, target)
        # The setting beside the time: what a user sets to reach the target with this integrator.
        cells = [f"{_number(best[n].wall_s):.3g} s ({_knob(best[n])})" if n in best else "-"
                 for n in lines_in_order]
        if best:
            winner = best[min(best, key=lambda n: _number(best[n].wall_s))]
            cells = [f"**{c}**" if n in best and tied(winner, best[n]) else c for n, c in zip(lines_in_order, cells)]
        lines.append(f"| {target:.0e} {length} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


#: A tighter setting whose position error is this many times a looser one's
#: is named under the table (the main job's pfvi s = 8 at epsilon 1e-8 has
#: 1.9 times its error at 1e-4).
LOOSER_RATIO = 1.5


def tighter_less_accurate(rows: Iterable[Run]) -> List[str]:
    """One sentence per line where a tighter setting (smaller epsilon or eps,
    more steps per period) ended farther from the reference than the looser
    one before it, with the steps of both."""
    by_line: Dict[str, List[Run]] = {}
    for r in rows:
        if r.status == "ok" and r.value is not None and math.isfinite(_number(r.position_error)):
            by_line.setdefault(r.label, []).append(r)
    out = []
    for label, runs in by_line.items():
        tight_last = sorted(runs, key=lambda r: -_number(r.value) if r.knob != "steps/period" else _number(r.value))
        pairs = [(a, b) for a, b in zip(tight_last, tight_last[1:])
                 if _number(b.position_error) > LOOSER_RATIO * _number(a.position_error)]
        if pairs:
            out.append(f"{label}: " + "; ".join(
                f"{_knob(b)} ends {_number(b.position_error):.2g} from the reference against "
                f"{_number(a.position_error):.2g} at {_knob(a)} ({b.steps} steps against {a.steps})"
                for a, b in pairs) + ".")
    return out


#: Why a pfvi line's error is not monotone in epsilon (measured on the main
#: job's comet: benchmarks/epsilon_match.py writes the run behind it).
PFVI_NOT_MONOTONE = (
    "Why for pfvi: at s = 8 every epsilon above 1.2e-7 runs at 1.2e-7 (epsilon_effective: the steps are held at "
    "their cap), and down to about 1e-8 the step track hardly changes (on the comet 101 to 106 steps), so the "
    "error does not follow epsilon. It is the sum of the steps' signed errors, almost all of it along the "
    "track (the comet's phase), and its sign changes from one epsilon to the next: on the comet -2.5e-7 AU at "
    "1e-6, +1.3e-7 at 3.2e-8, -4.7e-7 at 1e-8, +6.1e-8 at 3.2e-9, +7.9e-11 at 3.2e-10 and -4.1e-9 at 1e-10 "
    "(docs/epsilon-match.md). The error falls with epsilon as the order says (14 at s = 8) only between "
    "settings far enough apart, about a factor 100 in epsilon; a single setting can land about 50 times off "
    "that trend either way.")


#: How each family gets to its accuracy: the reason behind its cost per unit of accuracy.
HOW = {
    "pfvi": "pfvi is implicit: each step solves its stage equations by iteration (several force evaluations per "
            "stage), with adaptive steps from a time-symmetric step density (the default: one solve per "
            "step) or, on the lines marked reversible, from osculating circles (several trial steps per "
            "step); it is of order 2s - 2 (s = 4: 6, s = 6: 10, s = 8: 14)",
    "ias15": "IAS15 is a 15th-order adaptive predictor-corrector: long steps, each of several force evaluations",
    "bs": "BS (Gragg-Bulirsch-Stoer) extrapolates to high order with adaptive steps",
    "whfast": "WHFast takes fixed steps of an exact Kepler drift and interaction kicks (second order); its "
              "error is that of the kicks, so it is cheap where the motion is nearly Keplerian and the step "
              "resolves the closest approach",
    "leapfrog": "LEAPFROG takes fixed second-order steps: an eccentric orbit's pericentre needs very many of them",
    "trace": "TRACE (2024) takes WHFast-like fixed steps in democratic heliocentric coordinates and switches "
             "reversibly to BS for close encounters (within r_crit_hill = 3 Hill radii) and for pericentre "
             "passages that the step does not resolve (peri_crit_eta = 1); REBOUND's defaults",
    "mercurius": "MERCURIUS takes WHFast-like fixed steps in democratic heliocentric coordinates and hands "
                 "close encounters (within r_crit_hill = 3 Hill radii) to IAS15; REBOUND's defaults. A "
                 "pericentre passage is not an encounter to it",
}


def whfast_caveat(results: Results) -> str:
    """A sentence on what WHFast's result means on this scene, or "" if nothing needs saying."""
    scene = results.scene
    if not any(r.family == "whfast" for r in results.rows):
        return ""
    if scene.name == "kepler" or (scene.name == "custom" and scene.build().N == 2):
        return ("**WHFast caveat**: this is a pure two-body Kepler problem, which WHFast solves exactly "
                "(its Kepler drift is the solution and the kick vanishes), so its error is round-off at any "
                "step: its rank here says nothing about perturbed problems. For a fair ranking run "
                "`rebound-pfvi compare --scene comet`.")
    if scene.name == "comet":
        return ("WHFast is not exact here: Jupiter's pull, and the Sun's offset from the Sun-Jupiter "
                "barycentre about which its Jacobi coordinates drift the comet, enter as kicks, largest at the "
                "comet's pericentre, and its fixed steps (counted per comet period) cross that passage in few "
                "steps.")
    return ""


def _times(ratio: float) -> str:
    """A ratio of wall times, with the digits that tell a tie (TIE_RATIO) from a win."""
    return f"{ratio:.0f}x" if ratio >= 10 else f"{ratio:.1f}x" if ratio >= 2 else f"{ratio:.2f}x"


def _per_evaluation(row: Run) -> float:
    return _number(row.wall_s) / row.force_evaluations * 1e6 if row.force_evaluations else math.nan


def conclusions(results: Results, floor: float = 0.0, length: str = "AU") -> List[str]:
    """One sentence per position error: who is fastest (or which lines tie
    within the run-to-run noise, TIE_RATIO), by how much, and the measured
    reason (force evaluations and wall time per evaluation against the best
    pfvi run). Every ratio is another run's wall time over the fastest's."""
    sentences = []
    for target in [t for t in TARGETS if t > floor]:
        best = fastest(results.rows, target)
        if not best:
            sentences.append(f"To {target:.0e} {length}: no run of the sweep gets there.")
            continue
        order = sorted(best.values(), key=lambda r: _number(r.wall_s))
        win = order[0]
        win_s = _number(win.wall_s)
        ties = [r for r in order[1:] if tied(win, r)]
        if ties:
            names = ", ".join(f"{r.label} ({_knob(r)}) {_number(r.wall_s):.3g} s" for r in ties)
            text = (f"To {target:.0e} {length}: a tie within the run-to-run noise (wall times within "
                    f"{TIE_RATIO:g}x): {win.label} ({_knob(win)}) {win_s:.3g} s, {names}")
        else:
            text = f"To {target:.0e} {length}: {win.label} ({_knob(win)}) is fastest, {win_s:.3g} s"
        # The runner-up of another family beyond the tie; pfvi gets its own clause unless it is among the first.
        first = [win] + ties
        other = next((r for r in order[len(first):] if r.family != win.family
                      and (win.family == "pfvi" or r.family != "pfvi")), None)
        if other:
            text += (f"; next, {other.label} ({_knob(other)}) takes {_times(_number(other.wall_s) / win_s)} "
                     f"the wall time of {win.label}")
        pfvi = next((r for r in order if r.family == "pfvi"), None)
        ran_pfvi = any(r.family == "pfvi" for r in results.rows)
        if all(r.family != "pfvi" for r in first) and ran_pfvi:
            if pfvi is None:
                text += "; no pfvi run of the sweep gets there"
            else:
                pfvi_s = _number(pfvi.wall_s)
                text += (f"; the fastest pfvi, {pfvi.label} ({_knob(pfvi)}), takes {pfvi_s:.3g} s, "
                         f"{_times(pfvi_s / win_s)} the wall time of {win.label}: {win.label} needs "
                         f"{win.force_evaluations} force evaluations at {_per_evaluation(win):.2g} µs each, "
                         f"pfvi {pfvi.force_evaluations} at {_per_evaluation(pfvi):.2g} µs")
        elif other:
            lead = pfvi if pfvi is not None and pfvi in first else win
            text += (f"; {lead.label} needs {lead.force_evaluations} force evaluations at "
                     f"{_per_evaluation(lead):.2g} µs each, {other.label} {other.force_evaluations} at "
                     f"{_per_evaluation(other):.2g} µs")
        sentences.append(text + ".")
    return sentences


def conclusions_section(results: Results, floor: float = 0.0, length: str = "AU") -> str:
    """The page's answer in words: who is fastest at each accuracy, why, and the WHFast caveat."""
    families = list(dict.fromkeys(r.family for r in results.rows))
    parts = ["\n".join(f"- {s}" for s in conclusions(results, floor, length)),
             "Why (the wall time per force evaluation above is one evaluation plus the integrator's own work "
             "per evaluation):\n\n" + "\n".join(f"- {HOW[f]}." for f in families if f in HOW)]
    caveat = whfast_caveat(results)
    if caveat:
        parts.append(caveat)
    return "\n\n".join(parts)


def bodies_section(rows: Iterable[Run]) -> str:
    """Each body's largest error over the outputs (km), against each
    reference (the solar system: DE421 and IAS15), one table per reference;
    "" if no run measured them."""
    measured = [(r, r.bodies) for r in rows if r.status == "ok" and r.bodies]
    if not measured:
        return ""
    parts = []
    for against in measured[0][1]:
        bodies = list(measured[0][1][against])
        lines = [f"Against {against} (km):", "",
                 "| integrator | setting | wall [s] | " + " | ".join(bodies) + " |",
                 "|---|---|---|" + "---|" * len(bodies)]
        for r, errors_by_reference in measured:
            errors = errors_by_reference[against]
            lines.append(f"| {r.label} | {_knob(r)} | {_number(r.wall_s):.3g} | "
                         + " | ".join(f"{errors[b]:.3g}" for b in bodies) + " |")
        parts.append("\n".join(lines))
    return "\n\n".join(parts)


def warnings_section(rows: Iterable[Run]) -> str:
    """REBOUND's warnings, each explained once, with the runs that raised it."""
    from .runs import explain_warning

    by_message: Dict[str, List[str]] = {}
    for r in rows:
        for message in r.warnings:
            by_message.setdefault(message, []).append(f"{r.label} {_knob(r)}")
    lines = []
    for m, runs in by_message.items():
        meaning = explain_warning(m)
        # (a warning with no explanation of its own is quoted once, not twice)
        said = "" if meaning == m else f": {meaning.rstrip('.')}"
        lines.append(f"- \"{m}\" ({', '.join(runs)}){said}.")
    return "\n".join(lines)


def verdict_section(results: Results) -> str:
    """What the verdicts mean, the tolerance, and the runs counted per verdict and integrator."""
    from . import verdict

    tolerance = getattr(results.scene, "tolerance", verdict.DEFAULT)
    shown = verdict.VERDICTS if results.budget is not None else verdict.VERDICTS[:-1]
    budget = (f" Budget: {results.budget:g} s of wall time per setting." if results.budget is not None
              else " No budget was set (--budget), so no run can be over budget.")
    return ("Each run's verdict: " + "; ".join(f"**{v}**: {verdict.MEANING[v]}" for v in shown) + "." + budget
            + " "
            + f"Tolerance: {tolerance.describe()} at t_end. A sweep includes loose settings on purpose, "
            "so inaccurate runs are expected at its loose end; a refused run is pfvi declining a step it "
            "cannot take (its message is in the table below).\n\n"
            + verdict.markdown_counts(results.verdict_counts()))


def plot(results: Results, path: str) -> None:
    """Work-precision diagram: position error and largest energy error against wall time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in results.rows if r.status == "ok"]
    lines_in_order = list(dict.fromkeys(r.label for r in rows))
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    styles = {"pfvi": "-", "ias15": "--", "whfast": ":", "leapfrog": "-.", "bs": (0, (5, 1, 1, 1)),
              "trace": (0, (3, 1, 1, 1, 1, 1)), "mercurius": (0, (1, 2))}
    markers = "osD^v<>ph*"
    floor = 1e-17  # exact zeros (WHFast's energy on two bodies) are drawn at the floor
    for k, name in enumerate(lines_in_order):
        sel = sorted((r for r in rows if r.label == name), key=lambda r: _number(r.wall_s))
        family = sel[0].family
        # Points joined in order of wall time, each labelled with its knob's value (the knob is in the legend).
        for ax, errors in zip(axes, ([r.position_error for r in sel], [r.energy_error_max for r in sel])):
            ys = [max(_number(e), floor) for e in errors]
            (drawn,) = ax.loglog([r.wall_s for r in sel], ys, linestyle=styles.get(family, "-"),
                                 marker=markers[k % len(markers)], label=f"{name} ({sel[0].knob})",
                                 mfc="none" if family != "pfvi" else None)
            for r, y in zip(sel, ys):
                ax.annotate(f"{r.value:g}", (_number(r.wall_s), y), textcoords="offset points", xytext=(2, 2),
                            fontsize=5, color=drawn.get_color(), alpha=0.8)
    axes[0].set_ylabel(f"position error at t_end [{length_unit(results)}]")
    axes[1].set_ylabel("largest relative energy error")
    for ax in axes:
        ax.set_xlabel("wall time [s] (best of %d)" % results.repeats)
        ax.grid(True, which="both", alpha=0.3)
    # The legend goes under both panels, outside them: inside either it
    # covered curves (the loose LEAPFROG, WHFast and seed lines run through
    # every corner of the energy panel).
    handles, labels = axes[0].get_legend_handles_labels()
    ncol = 3 if len(labels) > 4 else len(labels) or 1
    rows_of_legend = -(-len(labels) // ncol)
    fig.set_size_inches(12, 4.8 + 0.2 * rows_of_legend)
    fig.suptitle(results.scene.describe(), fontsize=9)
    fig.legend(handles, labels, loc="lower center", ncol=ncol, fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.04 * rows_of_legend, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def machine() -> Dict[str, Any]:
    import rebound

    return {"python": platform.python_version(), "rebound": rebound.__version__, "machine": platform.machine(),
            "cores": os.cpu_count()}


def _tighter_section(rows: List[Run]) -> str:
    notes = tighter_less_accurate(rows)
    if not notes:
        return ""
    text = "\nWhere a tighter setting ended less accurate than the looser one before it:\n\n"
    text += "\n".join(f"- {note}" for note in notes) + "\n"
    if any(note.startswith("pfvi") for note in notes):
        text += "\n" + PFVI_NOT_MONOTONE + "\n"
    return text


def write(results: Results, output: str, basename: Optional[str] = None,
          command: Optional[str] = None) -> Dict[str, str]:
    """Writes <basename>.json, .csv, .md and .png (if matplotlib is installed)
    into `output` (basename: the scene's slug, e.g. kepler-e0.95; a name
    without a folder, ValueError otherwise); returns the paths written."""
    base = os.path.join(output, file_name(results.scene.slug if basename is None else basename, "basename"))
    os.makedirs(output, exist_ok=True)
    data = results.to_dict()
    data["machine"] = machine()
    data["command"] = command
    paths = {}
    with open(base + ".json", "w") as f:
        json.dump(data, f, indent=1)
    paths["json"] = base + ".json"
    with open(base + ".csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=("scene", "family", "options") + COLUMNS, extrasaction="ignore")
        writer.writeheader()
        for r in results.rows:
            row = r.to_dict()
            writer.writerow({**row, "options": json.dumps(row["options"])})
    paths["csv"] = base + ".csv"
    png_note = ""
    try:
        plot(results, base + ".png")
        paths["png"] = base + ".png"
        # (the page links the figure only where there is one)
        png_note = f"![work-precision diagram]({os.path.basename(base)}.png)\n"
    except ImportError:
        png_note = "\n(No plot: matplotlib is not installed; pip install 'rebound_pfvi[plot]'.)\n"
    m = data["machine"]
    status = (f"**Interrupted**: {results.finished} of {len(results.settings)} runs finished.\n\n"
              if results.interrupted else f"**Nothing measured**: {results.failure}.\n\n" if results.failure else "")
    floor = results.reference.get("uncertainty", 0.0)
    length = length_unit(results)
    bodies = bodies_section(results.rows)
    bodies_text = (f"\n## Each body's error, the largest over the outputs\n\nEvery run stops at each output "
                   f"and reads the positions there, inside its timed loop (the wall times above include "
                   f"it).\n\n{bodies}\n" if bodies else "")
    text = f"""# {results.scene.describe()}

{status}Generated by `{command or 'rebound_pfvi.compare.run'}` on {m['cores']} cores (Python {m['python']},
rebound {m['rebound']}); the sweep took {results.wall_s:.1f} s with {results.workers} worker(s)
({results.scheduler}). Wall times are the best of {results.repeats} repeats, with the runs of the sweep
sharing the machine's cores: compare them within this page only.

Reference: {results.reference['how']}; its uncertainty: {floor:.1e} {length}. Energy: the largest relative
error over {results.samples} evenly spaced times (an untimed rerun, which also counts force evaluations
through a callback in additional_forces), and the final one. Position error: the largest distance of a
particle from its reference position at t_end (Kepler: of the relative position).

## Verdicts

{verdict_section(results)}

## Who is fastest at each accuracy, and why

{conclusions_section(results, floor, length)}

## Fastest run of each integrator that reaches a position error, and its setting

{summary_table(results.rows, floor, length)}
{_tighter_section(results.rows)}
{png_note}{bodies_text}
## Every run

{markdown_table(results.rows, length)}
""" + (f"""
## Warnings

{warnings_section(results.rows)}
""" if any(r.warnings for r in results.rows) else "")
    with open(base + ".md", "w") as f:
        f.write(text)
    paths["md"] = base + ".md"
    return paths


# --- the stability report (rebound-pfvi stability) ---------------------------

def stability_verdict_counts(report: StabilityReport) -> Dict[str, Dict[str, int]]:
    """{integrator: {verdict: runs}} over every case of the report."""
    from .runs import count

    return count(report.rows)


def stability_markdown(report: StabilityReport, command: Optional[str] = None) -> str:
    """The report as markdown: the verdicts counted per integrator, then one table per case."""
    from . import verdict
    from .stability import cases

    lines = ["# Stability report: extreme cases", ""]
    if command:
        lines += [f"Produced by `{command}` in {report.wall_s:.0f} s (2 cores here); every run in its own "
                  f"process with a budget of {report.budget:g} s of integration.", ""]
    lines += ["## Verdicts", "",
              "Each run's verdict: " + "; ".join(f"**{v}**: {verdict.MEANING[v]}" for v in verdict.VERDICTS)
              + f". Tolerance unless a case says otherwise: {verdict.DEFAULT.describe()} (the reference's "
              "distance at the time reached: the size of the orbit where the body is).", "",
              verdict.markdown_counts(stability_verdict_counts(report)), ""]
    lines += ["Columns: the verdict; what happened (the error against the tolerance, the refusal's message, or "
              "the budget) and what the integrator counted; t reached as a fraction of the case's end; "
              "relative energy error at the end and the largest over 100 checkpoints (for the parabola, "
              "relative to |T0| + |V0|); largest position error against the reference at the time reached "
              "(AU; for two-body cases the relative vector); steps; wall time.", ""]
    by_case: Dict[str, List[Run]] = {}
    for row in report.rows:
        by_case.setdefault(row.scene, []).append(row)
    for name, rows in by_case.items():
        case = cases()[name]
        ref = report.references.get(name, {})
        lines += [f"## {name}", "", case.title + ".", ""]
        how = ref.get("how", "")
        if ref.get("uncertainty"):
            how += f" = {ref['uncertainty']:.2g} AU"
        tolerance = "" if case.tolerance == verdict.DEFAULT else f"Tolerance: {case.tolerance.describe()}. "
        lines += [f"Reference: {how}. " + tolerance
                  + (f"Fixed steps: {case.fixed_dt:.3g} yr (pfvi epsilon = 0, WHFast). " if case.fixed_dt else
                     f"WHFast dt = {case.whfast_step:.3g} yr. ") + case.note, ""]
        lines += ["| integrator | verdict | what happened | t reached | energy error (end / max) | position error "
                  "[AU] | steps | wall s |", "|---|---|---|---|---|---|---|---|"]
        for r in rows:
            lines.append(f"| {r.label} | {r.verdict or '-'} | {r.what_happened.replace('|', '/')} | "
                         f"{fmt(r.fraction, '.3g')} | {fmt(r.energy_error_final)} / "
                         f"{fmt(r.energy_error_max)} | {fmt(r.position_error)} | {fmt(r.steps, 'd')} | "
                         f"{fmt(r.wall_s, '.3g')} |")
        lines.append("")
    return "\n".join(lines)


def write_stability(report: StabilityReport, directory: Any, command: Optional[str] = None) -> List[pathlib.Path]:
    """stability.json and stability.md in `directory`; returns their paths."""
    import json
    import pathlib

    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = [directory / "stability.json", directory / "stability.md"]
    data = report.to_dict()  # its rows without the positions, which only the verdict needed
    data["command"] = command
    paths[0].write_text(json.dumps(data, indent=1, default=str))
    paths[1].write_text(stability_markdown(report, command))
    return paths
