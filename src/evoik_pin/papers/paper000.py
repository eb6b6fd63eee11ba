"""Paper 000: multi-objective DE for the 4-DOF Crustcrawler AX-18 (Rodriguez, Saha, Romero-Hdz & Ortega, 2016):
Table 2 (five targets: binary GA, algebraic method, the paper's ``mode``) and Figs. 3-6 (diversity, weights,
fitness, front and error of three configurations); our readings and results: docs/REPRODUCTION.md, "Paper 000".
"""

from __future__ import annotations

import numpy as np

from ..api import solve
from ..robot import load_robot
from .reporting import PaperReport, RunContext, Table, derive_rng, dress, tuple_text

PAPER_ID = "000"
TITLE = "A multi-objective differential evolution algorithm for robot inverse kinematics"

ROBOT = "ax18"
CM, MM = 0.01, 0.001

#: Table 2 targets (cm).
TARGETS_CM = [(10.0, 10.0, 10.0), (0.0, 7.5, 12.0), (2.0, 13.0, -5.0), (-6.0, 9.5, 4.3), (3.0, -7.0, 13.0)]
#: Table 2 as printed: reached positions (cm) of GA, AM and the proposed DE for each target.
PAPER_TABLE2 = {
    (10.0, 10.0, 10.0): {"GA": (10.8, 8.8, 11.9), "AM": (10.1, 10.1, 10.0), "DE": (10.0, 10.0, 10.0)},
    (0.0, 7.5, 12.0): {"GA": (2.7, 7.4, 11.3), "AM": (0.0, 6.8, 11.3), "DE": (0.0, 7.5, 12.0)},
    (2.0, 13.0, -5.0): {"GA": (2.9, 15.4, -6.1), "AM": (2.1, 13.5, -5.8), "DE": (2.0, 13.0, -5.0)},
    (-6.0, 9.5, 4.3): {"GA": (-9.5, 9.0, 3.9), "AM": (-5.9, 9.3, 4.3), "DE": (-6.0, 9.5, 4.3)},
    (3.0, -7.0, 13.0): {"GA": (2.0, -9.5, 16.1), "AM": (3.0, -7.0, 13.0), "DE": (3.0, -7.0, 13.0)},
}
#: The three configurations of Figs. 3-6, as ``mode`` variants.
CONFIGS = {"(a) fixed crossover, normal mutation": "fixed",
           "(b) binomial, no trigonometric": "binomial",
           "(c) binomial + trigonometric": "binomial-trigonometric"}
METHOD_LABELS = {"GA": "GA (ga-binary)", "AM": "AM (algebraic)", "DE": "DE (mode, binomial-trigonometric)"}
SERIES = ("diversity", "w1", "w2", "best_fitness", "best_position_error")


def _settings(quick: bool) -> dict:
    return {
        "robot": ROBOT, "targets_cm": TARGETS_CM, "runs_per_target_and_method": 2 if quick else 10,
        "q_init_deg": [0.0, 0.0, 0.0, 0.0],
        "mode": {"population": 150, "max_generations": 200, "mutation_probability": 0.2, "crossover_rate": 0.8,
                 "scale_factor": 0.2, "trigonometric_probability": 0.125, "adaptive": True,
                 "variants": dict(CONFIGS), "tolerance_m": 0.0,
                 "note": "Mt is not given by the paper; 0.125 was measured on random reachable targets "
                         "(see evoik_pin.solvers.paper.mode)"},
        "ga_binary": {"population": 200, "elite": 100, "max_generations": 100 if quick else 400, "bits": 9,
                      "encoding": "sign-magnitude", "tolerance_m": 0.0},
        "algebraic": {"phi_step_deg": 0.5, "note": "deterministic: one run"},
        "success_threshold_mm": 1.0,
        "figures": "medians over all runs of the five targets per configuration; Fig. 6(a): first (c) run "
                   "on (10, 10, 10)",
    }


def _part(spec: dict) -> list[dict]:
    """``spec["runs"]`` runs of one method on one target (a top-level job for ``ctx.map_parallel``)."""
    robot = load_robot(ROBOT)
    t_cm, method = spec["t_cm"], spec["method"]
    target = np.array(t_cm) * CM
    rng = derive_rng(spec["seed"], "000", method, *map(str, t_cm))
    kw = ({"method": "ga-binary", **spec["ga_kw"]} if method == "GA"
          else {"method": "mode", "q0": np.zeros(robot.n), "variant": method, **spec["mode_kw"]})
    return [_record(robot, solve(robot, target, seed=rng, tolerance=0.0, **kw)) for _ in range(spec["runs"])]


def _record(robot, res) -> dict:
    p = np.asarray(robot.positions_batch(res.q[None])[0])
    return {"error": float(res.position_error), "reached": p, "q": res.q.copy(),
            "displacement": float(np.abs(res.q).max()), "generations": int(res.generations),
            "time": float(res.time_s), "result": res}


def _summary(runs: list[dict]) -> dict:
    e = np.array([r["error"] for r in runs])
    median_run = runs[int(np.argsort(e, kind="stable")[(len(e) - 1) // 2])]
    return {"runs": len(e), "success": float(np.mean(e < MM)), "median_error": float(np.median(e)),
            "max_error": float(e.max()), "reached": median_run["reached"], "reached_error": median_run["error"],
            "median_displacement": float(np.median([r["displacement"] for r in runs])),
            "mean_time": float(np.mean([r["time"] for r in runs]))}


def _median_series(runs: list[dict], key: str) -> np.ndarray:
    curves = [np.asarray(r["result"].history[key], float) for r in runs]
    length = min(len(c) for c in curves)
    return np.median(np.stack([c[:length] for c in curves]), axis=0)


def run(ctx: RunContext) -> PaperReport:
    """Reproduce paper 000's Table 2 and Figs. 3-6 (see the module docstring)."""
    s = _settings(ctx.quick) | {"jobs": ctx.jobs}
    robot = load_robot(ROBOT)
    report = PaperReport(PAPER_ID, TITLE, ctx.quick, ctx.seed, settings=s)
    runs, q_init = s["runs_per_target_and_method"], np.zeros(robot.n)
    mode_kw = {k: v for k, v in s["mode"].items() if k not in ("variants", "tolerance_m", "note")}
    ga_kw = {k: s["ga_binary"][k] for k in ("population", "elite", "max_generations", "bits", "encoding")}

    results: dict[tuple, dict[str, list[dict]]] = {}
    specs = [{"seed": ctx.seed, "t_cm": t, "method": m, "runs": runs, "mode_kw": mode_kw, "ga_kw": ga_kw}
             for m in ["GA", *CONFIGS.values()] for t in TARGETS_CM]  # the slow GA parts first
    for spec, out in zip(specs, ctx.map_parallel(_part, specs, "000 Table 2 / Figs. 3-6"), strict=True):
        results.setdefault(spec["t_cm"], {})[spec["method"]] = out
    for t_cm in TARGETS_CM:
        results[t_cm]["AM"] = [_record(robot, solve(robot, np.array(t_cm) * CM, method="algebraic", q0=q_init))]

    rows, paper_rows, summary = [], [], {}
    for t_cm in TARGETS_CM:
        for key, method in (("GA", "GA"), ("AM", "AM"), ("DE", "binomial-trigonometric")):
            sm = _summary(results[t_cm][method])
            summary[f"{t_cm} {key}"] = sm
            rows.append([tuple_text(t_cm, ".1f"), METHOD_LABELS[key], tuple_text(sm["reached"] / CM, ".2f"),
                         sm["reached_error"] / CM, sm["runs"], sm["success"], sm["median_error"] / MM,
                         sm["max_error"] / MM, np.degrees(sm["median_displacement"])])
            reached = PAPER_TABLE2[t_cm][key]
            paper_rows.append([tuple_text(t_cm, ".1f"), METHOD_LABELS[key], tuple_text(reached, ".1f"),
                               float(np.linalg.norm(np.subtract(reached, t_cm))), None, None, None, None, None])
    report.tables.append(Table(
        "table2", "Table 2 - target positions and the end-effector positions reached (GA, AM, proposed DE)",
        ["target (cm)", "method", "reached position (cm)", "error (cm)", "runs", "within 1 mm (fraction)",
         "median error (mm)", "max error (mm)", "median max displacement (deg)"],
        rows, paper_rows=paper_rows, formats=[None, None, None, ".3f", None, ".2f", ".3f", ".3f", ".1f"],
        note=("Reached position and error: the run with the median error (the paper prints one run to 1 decimal; "
              "its errors here are computed from its printed positions, so a printed 'exact' hit means within "
              "about 0.09 cm). AM is deterministic (one run); 'max displacement' is paper 000's second objective, "
              "max |q_k - q_init,k| with q_init = 0.")))

    pooled = {label: [r for t in TARGETS_CM for r in results[t][v]] for label, v in CONFIGS.items()}
    cfg_rows = [[label, c["runs"], c["success"], c["median_error"] / MM, c["max_error"] / MM, c["mean_time"]]
                for label, c in zip(pooled, map(_summary, pooled.values()), strict=True)]
    report.tables.append(Table(
        "configurations", "Fig. 6(b) in numbers - the three DE configurations over all five targets",
        ["configuration", "runs", "within 1 mm (fraction)", "median error (mm)", "max error (mm)", "time per run (s)"],
        cfg_rows, formats=[None, None, ".2f", ".4f", ".3f", ".3f"],
        note="The paper shows these as curves only (Fig. 6b: (c) reaches the lowest position error)."))

    curves = {label: {k: _median_series(rs, k) for k in SERIES} for label, rs in pooled.items()}
    report.figures += [_fig_diversity(ctx, curves), _fig_weights(ctx, curves), _fig_fitness(ctx, curves),
                       _fig_front(ctx, results[TARGETS_CM[0]]["binomial-trigonometric"][0]["result"], curves)]

    report.notes += _notes(summary, cfg_rows, curves, runs)
    report.data.update({
        "runs": {f"{t}": {m: [{"error_m": r["error"], "reached_m": r["reached"], "q_rad": r["q"],
                               "max_displacement_rad": r["displacement"], "generations": r["generations"],
                               "time_s": r["time"]} for r in rs] for m, rs in results[t].items()}
                 for t in TARGETS_CM},
        "median_curves": curves,
        "summary": summary,
    })
    return report


def _notes(summary: dict, cfg_rows: list, curves: dict, runs: int) -> list[str]:
    de, ga, am = ([summary[f"{t} {m}"] for t in TARGETS_CM] for m in ("DE", "GA", "AM"))
    paper_ga, paper_am = ([np.linalg.norm(np.subtract(PAPER_TABLE2[t][m], t)) for t in TARGETS_CM]
                          for m in ("GA", "AM"))
    n_ok = sum(round(d["success"] * d["runs"]) for d in de)
    c_label = list(CONFIGS)[2]
    hits = {label: np.nonzero(1.0 - c["w1"] <= 0.01)[0] for label, c in curves.items()}  # median w1 >= 0.99
    w_gen = {label: int(h[0]) if h.size else None for label, h in hits.items()}
    rates = ", ".join(f"{d['success']:.0%}" for d in de)
    medians = ", ".join(f"{d['median_error'] / MM:.3f}" for d in de)
    worst = max(d["max_error"] for d in de) / MM
    return [
        f"Proposed DE (configuration (c), paper settings): {n_ok} of {runs * len(TARGETS_CM)} runs within 1 mm "
        f"(per target {rates}); median errors {medians} mm, worst run {worst:.3f} mm. The paper prints each DE "
        "result as the target itself to 1 decimal (within ~0.9 mm).",
        "Trigonometric share Mt: the paper gives no value; ours, 0.125, was measured on random reachable targets "
        "(with Fan & Lampinen's 0.05, 94 % of Table 2 runs ended within 1 mm; docs/BENCHMARKS.md).",
        f"GA: our binary GA's median errors per target are {min(g['median_error'] for g in ga) / MM:.2f}-"
        f"{max(g['median_error'] for g in ga) / MM:.2f} mm (worst run {max(g['max_error'] for g in ga) / MM:.2f} mm) "
        f"against the paper's {min(paper_ga):.1f}-{max(paper_ga):.1f} cm. Its 9-bit angles move in 0.7 deg steps "
        "(2-4 mm of tip motion per step), so millimetres are its floor; the paper gives no crossover or mutation "
        "rates that could explain its centimetres.",
        f"AM: our algebraic method reaches every target to {max(a['max_error'] for a in am):.1e} m; the paper's misses "
        f"by up to {max(paper_am):.2f} cm (ours searches phi with both shoulder branches and refines it; the "
        "paper's formulas cannot be run as printed).",
        "Configurations (Fig. 6b): " + "; ".join(f"{r[0]} {r[2]:.0%} within 1 mm, median {r[3]:.3f} mm"
                                                 for r in cfg_rows)
        + ". As in the paper, (c) reaches the lowest position error: (a) and (b) lack the trigonometric donor that "
        "contracts the population, and stall at millimetres.",
        "Weights (Fig. 4): generation at which the median w1 exceeds 0.99: "
        + ", ".join(f"{k.split(' ')[0]} {v if v is not None else '> 200'}" for k, v in w_gen.items())
        + f". The paper reports (c) settling in under 50 generations; ours settles at {w_gen[c_label]} (w2 tends to 0 "
        "with the error of b, the individual closest to the target).",
        "Diversity (Fig. 3): mean range-scaled distance to the centroid (0.58 for a uniform population); the paper "
        "does not define its measure, so compare shapes, not values. Our readings of the pseudocode: "
        "evoik_pin.solvers.paper.mode and docs/BENCHMARKS.md.",
    ]


_COLORS = dict(zip(CONFIGS, ("tab:blue", "tab:orange", "tab:green"), strict=True))


def _fig_diversity(ctx, curves):
    fig, ax = ctx.new_figure(figsize=(6, 3.8))
    for label, c in curves.items():
        ax.plot(c["diversity"], label=label, color=_COLORS[label])
    dress(ax, "generation", "mean diversity (range-scaled)",
          "Mean population diversity (median over runs and targets)", legend=8)
    return ctx.save_figure(fig, "fig3_diversity", "Fig. 3 analogue: mean population diversity per generation, "
                                                  "three configurations")


def _fig_weights(ctx, curves):
    fig, axes = ctx.new_figure(1, 3, figsize=(11, 3.5), sharey=True)
    for ax, (label, c) in zip(axes, curves.items(), strict=True):
        ax.plot(c["w1"], label="w1 (position)")
        ax.plot(c["w2"], label="w2 (displacement)")
        dress(ax, "generation", "weight (median)" if ax is axes[0] else "", label, legend=8 if ax is axes[0] else None)
    return ctx.save_figure(fig, "fig4_weights", "Fig. 4 analogue: equitable weights w1, w2 per generation for "
                                                "(a) fixed crossover, (b) without and (c) with trigonometric mutation")


def _fig_fitness(ctx, curves):
    fig, ax = ctx.new_figure(figsize=(6, 3.8))
    for label, c in curves.items():
        ax.semilogy(np.maximum(c["best_fitness"], 1e-12), label=label, color=_COLORS[label])
    dress(ax, "generation", "best weighted cost w1 f1 + w2 f2 (minimized)",
          "Best individual's weighted cost (median over runs and targets)", legend=8, grid="both")
    return ctx.save_figure(fig, "fig5_best_fitness", "Fig. 5 analogue: best individual's fitness per generation "
                                                     "(our cost is minimized; the paper plots a maximized fitness)")


def _fig_front(ctx, res, curves):
    fig, axes = ctx.new_figure(1, 2, figsize=(11, 4))
    F = res.front.objectives
    axes[0].semilogx(np.maximum(F[:, 0] / MM, 1e-6), np.degrees(F[:, 1]), ".", ms=4)
    dress(axes[0], "position error (mm)", "max joint displacement from q_init (deg)",
          "(a) non-dominated set, (c) on target (10, 10, 10) cm", grid="both")
    for label, c in curves.items():
        axes[1].semilogy(np.maximum(c["best_position_error"] / MM, 1e-9), label=label, color=_COLORS[label])
    axes[1].axhline(1.0, color="k", lw=0.6, ls="--")
    dress(axes[1], "generation", "position error of the closest individual (mm)",
          "(b) median over runs and targets", legend=8, grid="both")
    return ctx.save_figure(fig, "fig6_front_and_error", "Fig. 6 analogue: (a) Pareto front of position error vs "
                                                        "maximum displacement; (b) position error per generation")


__all__ = ["CONFIGS", "PAPER_ID", "PAPER_TABLE2", "TARGETS_CM", "TITLE", "run"]
