#!/usr/bin/env python
"""Behaviour cloning on the two-way task (issue 49, item 3): docs/results/multimodal/README.md, written whole from
README.template.md and the committed files (nothing on the page is typed by hand).

    python docs/results/multimodal/clones.py [--check]          # the page and the figure from the committed files
    python docs/results/multimodal/clones.py --measure runs/multimodal

``--measure RUNS_DIR`` (on the machine that trained the clones; the checkpoints stay there) copies the small files
of RUNS_DIR's data/ (metadata.json), clone_flow/ and clone_gauss/ (config.yaml, eval.json, progress.jsonl) here,
reads the data's episodes, rolls each clone out from its checkpoint (the flow clone at N = 10 and N = 1, random
initial noise; the Gaussian clone's mean action and its sampled actions) and writes clones.json (per policy and
setting: episodes, success, the ways' counts, returns, where the failures end, a few downsampled trajectories) and
machine.json (the CPU, the load, the versions, the commit); then the page and the figure, as the default mode does.
The process wall times come from GNU time's output beside the runs (RUNS_DIR/<name>.time), when there; the
measuring is clone_rollouts.py's.
``--check`` writes nothing and reads only committed files: it compares the page with what they say.

Definitions (the task's geometry, refpo_warp/tasks/dmc/point_mass_wall_cfg.py): success = the mass's final position
(after the episode's last step) within the target's radius of the target; the way = the sign of y where the mass
first has x > 0 (left: y > 0; right: y < 0; none: it never got past the wall's middle); a failure's end: against
the wall (within a centimetre of the start-side face of the region the mass's centre cannot enter, |y| within that
region's half-length), past the wall (x > the region's half-thickness), back before the wall after passing it, or
before the wall without ever passing it.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
from clone_rollouts import (
    CLONES,
    EVERY,
    FIGURE,
    HERE,
    KEEP_FAILED,
    KEEP_PATHS,
    MACHINE,
    RESULTS,
    SETTINGS,
    TASK,
    WALL_TOUCH,
    measure,
)

TEMPLATE = HERE / "README.template.md"
Z95 = 1.959963984540054  # the two-sided 95 % normal quantile
COLOURS = {1: "#1f6fd1", -1: "#e07b1a", 0: "#c8102e"}


# ------------------------------------------------------------------------------------------------ statistics
def wilson(k: int, n: int) -> tuple[float, float]:
    """The Wilson score 95 % interval of a binomial proportion k / n."""
    if n == 0:
        return (math.nan, math.nan)
    p, z2 = k / n, Z95**2
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = Z95 * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def newcombe(k1: int, n1: int, k2: int, n2: int) -> tuple[float, float, float]:
    """p1 - p2 with Newcombe's 95 % interval from the two Wilson intervals (his method 10; independent samples)."""
    p1, p2 = k1 / n1, k2 / n2
    l1, u1 = wilson(k1, n1)
    l2, u2 = wilson(k2, n2)
    d = p1 - p2
    return (d, d - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2), d + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2))


def pct(k: int, n: int) -> str:
    """'k / n = p % [low, high]' with the Wilson interval."""
    if n == 0:
        return "--"
    low, high = wilson(k, n)
    return f"{k} / {n} = {100 * k / n:.0f} % [{100 * low:.0f}, {100 * high:.0f}]"


def mean_return(returns: list[float]) -> str:
    from refpo_warp.studies.reports.intervals import mean_estimate

    return mean_estimate(returns).text(0)


# ------------------------------------------------------------------------------------------------ the page
def table(res: dict) -> str:
    rows = [
        (
            "| policy | episodes | success [95 %] | left [95 %] | right [95 %] | neither way | left among the passes "
            "[95 %] | return, mean [95 %] |"
        ),
        "|---|---|---|---|---|---|---|---|",
    ]
    for key, _, label in SETTINGS:
        s = res["settings"][key]
        n, passed = s["episodes"], s["left"] + s["right"]
        rows.append(
            f"| {label} | {n} | {pct(s['success'], n)} | {pct(s['left'], n)} | {pct(s['right'], n)} | "
            f"{s['none']} | {pct(s['left'], passed)} | {mean_return(s['returns'])} |"
        )
    return "\n".join(rows)


def failures_table(res: dict) -> str:
    rows = [
        (
            "| policy | failures | against the wall (median, max of abs(y), m) | past the wall, off the target (median "
            "distance, m) | passed, then back before the wall | never passed | failures that went past the wall more "
            "than once |"
        ),
        "|---|---|---|---|---|---|---|",
    ]
    for key, _, label in SETTINGS:
        s = res["settings"][key]
        e, y, far = s["failure_ends"], s["failure_at_wall_abs_y"], s["failure_past_wall_distance_median"]
        ys = f" ({y['median']:.3f}, {y['max']:.3f})" if y["median"] is not None else ""
        fars = f" ({far:.3f})" if far is not None else ""
        rows.append(
            f"| {label} | {s['episodes'] - s['success']} | {e['at_wall']}{ys} | {e['past_wall']}{fars} | "
            f"{e['back_before_wall']} | {e['never_passed']} | {s['failures_passed_more_than_once']} |"
        )
    return "\n".join(rows)


def ways_table(res: dict) -> str:
    rows = ["| policy | successes by the left way | successes by the right way |", "|---|---|---|"]
    for key, _, label in SETTINGS:
        s = res["settings"][key]
        rows.append(f"| {label} | {pct(s['success_left'], s['left'])} | {pct(s['success_right'], s['right'])} |")
    return "\n".join(rows)


def verdict(d: tuple[float, float, float], what: str) -> str:
    low, high = d[1], d[2]
    if low > 0:
        return f"higher {what}: the interval lies above zero"
    if high < 0:
        return f"lower {what}: the interval lies below zero"
    return "the interval holds zero: these episodes do not separate them"


def comparisons(res: dict) -> tuple[str, dict]:
    st = res["settings"]
    label = {k: lab for k, _, lab in SETTINGS}
    rows = ["| comparison | quantity | difference, points [95 %] | what it says |", "|---|---|---|---|"]
    found = {}
    for x, y in (("flow_N10", "gauss_mean"), ("flow_N10", "gauss_sample"), ("flow_N10", "flow_N1")):
        d = newcombe(st[x]["success"], st[x]["episodes"], st[y]["success"], st[y]["episodes"])
        found[f"success_{x}_{y}"] = d
        rows.append(
            f"| {label[x]} − {label[y]} | success | {100 * d[0]:+.0f} [{100 * d[1]:+.0f}, {100 * d[2]:+.0f}] | "
            f"{verdict(d, 'success for the first')} |"
        )
    for x in ("flow_N10", "flow_N1"):
        s = st[x]
        d = newcombe(s["success_right"], s["right"], s["success_left"], s["left"])
        found[f"ways_{x}"] = d
        rows.append(
            f"| {label[x]}: right-way passes − left-way passes | success | {100 * d[0]:+.0f} [{100 * d[1]:+.0f}, "
            f"{100 * d[2]:+.0f}] | {verdict(d, 'success by the right way')} |"
        )
    for x in ("flow_N10", "flow_N1", "gauss_mean", "gauss_sample"):
        a, b = st[x], st["data"]
        na, nb = a["left"] + a["right"], b["left"] + b["right"]
        if na == 0:
            rows.append(f"| {label[x]} − data | left among the passes | -- (no pass) | -- |")
            continue
        d = newcombe(a["left"], na, b["left"], nb)
        found[f"left_{x}"] = d
        rows.append(
            f"| {label[x]} − data | left among the passes | {100 * d[0]:+.0f} [{100 * d[1]:+.0f}, "
            f"{100 * d[2]:+.0f}] | {verdict(d, 'left share than the data')} |"
        )
    return "\n".join(rows), found


def figure(res: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from refpo_warp.utils.atomic_files import save_figure

    geo = res["geometry"]
    fig, axes = plt.subplots(1, len(SETTINGS), figsize=(3.3 * len(SETTINGS), 4.3), sharey=True)
    for ax, (key, _, label) in zip(axes, SETTINGS):
        s = res["settings"][key]
        t, half, a, b = geo["wall_half_thickness"], geo["wall_half_length"], geo["grown_a"], geo["grown_b"]
        arena, spread = geo["arena"], geo["start_spread"]
        ax.add_patch(plt.Rectangle((-t, -half), 2 * t, 2 * half, color="#5a4632", zorder=3))
        ax.add_patch(plt.Rectangle((-a, -b), 2 * a, 2 * b, fill=False, ls=":", ec="#5a4632", zorder=3))
        ax.add_patch(plt.Rectangle((-arena, -arena), 2 * arena, 2 * arena, fill=False, ec="k", lw=1.0))
        ax.add_patch(plt.Circle((geo["target_x"], 0), geo["target_radius"], color="#2a9d3a", zorder=4))
        ax.add_patch(
            plt.Rectangle((geo["start_x"] - spread, -spread), 2 * spread, 2 * spread, fill=False, ec="#444", zorder=4)
        )
        for trace, w in zip(s["paths"], s["way"]):
            xy = np.array(trace)
            ax.plot(xy[:, 0], xy[:, 1], color=COLOURS[w], lw=1.0, alpha=0.9, zorder=5)
        for trace, w in zip(s["failed_paths"], s["failed_way"]):
            xy = np.array(trace)
            ax.plot(xy[:, 0], xy[:, 1], color=COLOURS[w], lw=0.9, ls="--", alpha=0.9, zorder=5)
        final = np.array(s["final"])
        hit = np.hypot(final[:, 0] - geo["target_x"], final[:, 1]) <= geo["target_radius"]
        ax.scatter(*final[~hit].T, s=9, marker="x", color="k", lw=0.8, zorder=6)
        n = s["episodes"]
        ax.set_title(
            f"{label}\nsuccess {100 * s['success'] / n:.0f} %, left {100 * s['left'] / n:.0f} %, "
            f"right {100 * s['right'] / n:.0f} %",
            fontsize=8.5,
        )
        ax.set_xlim(-0.3, 0.3)
        ax.set_ylim(-0.3, 0.3)
        ax.set_aspect("equal")
        ax.set_xticks([-0.2, -0.1, 0.0, 0.1, 0.2])
        ax.set_xlabel("x (m)")
    axes[0].set_ylabel("y (m)")
    handles = [
        plt.Line2D([], [], color=COLOURS[1], label="passed left (y > 0)"),
        plt.Line2D([], [], color=COLOURS[-1], label="passed right (y < 0)"),
        plt.Line2D([], [], color=COLOURS[0], label="never past the wall"),
        plt.Line2D([], [], ls="--", color="#666", label=f"the first {KEEP_FAILED} failed episodes"),
        plt.Line2D([], [], ls="", marker="x", color="k", label="end of a failed episode (all episodes)"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8.5, frameon=False, bbox_to_anchor=(0.5, 0.0))
    fig.suptitle(
        f"{TASK}: the first {KEEP_PATHS} episodes of each policy, solid, and its first {KEEP_FAILED} failed ones, "
        f"dashed (every {EVERY}th position); green: the target",
        fontsize=9.5,
    )
    fig.tight_layout(rect=(0, 0.1, 1, 0.97))
    save_figure(fig, path, dpi=110)
    plt.close(fig)


def read_yaml(path: Path) -> dict:
    import yaml

    return yaml.safe_load(path.read_text())


def mix_phrase(d: tuple[float, float, float]) -> str:
    """What a difference of left shares (a policy's minus the data's) says."""
    if d[1] > 0:
        return "more often left than the data (the difference's interval lies above zero)"
    if d[2] < 0:
        return "less often left than the data (the difference's interval lies below zero)"
    return "a mix these episodes do not tell apart from the data's (the difference's interval holds zero)"


def success_phrase(d: tuple[float, float, float], other: str) -> str:
    if d[1] > 0:
        return f"more often than {other} (the difference's interval lies above zero)"
    if d[2] < 0:
        return f"less often than {other} (the difference's interval lies below zero)"
    return f"as often as {other}, as far as these episodes tell (the difference's interval holds zero)"


ENDS = {
    "at_wall": "against the wall",
    "past_wall": "past the wall, off the target",
    "back_before_wall": "back before the wall after passing it",
    "never_passed": "before the wall, never past it, not against it",
}


def where_fail(s: dict) -> str:
    """Where most of a setting's failures end: 'k of n end <where>'."""
    n = s["episodes"] - s["success"]
    if n == 0:
        return "none fails"
    key = max(ENDS, key=lambda k: s["failure_ends"][k])
    k = s["failure_ends"][key]
    if k == n:
        return f"all {n} of its failures end {ENDS[key]}"
    most = "most" if 2 * k > n else "the largest group"
    return f"{most} of its {n} failures ({k}) end {ENDS[key]}"


def failed_below(s: dict, geo: dict) -> int:
    """How many of a setting's failed episodes end below the target's axis (y < 0)."""
    final = np.array(s["final"])
    fail = np.hypot(final[:, 0] - geo["target_x"], final[:, 1]) > geo["target_radius"]
    return int((fail & (final[:, 1] < 0)).sum())


def way_phrase(d: tuple[float, float, float]) -> str:
    if d[2] < 0:
        return "its right-way passes reach the target less often than its left-way ones (the interval lies below zero)"
    if d[1] > 0:
        return "its right-way passes reach the target more often than its left-way ones (the interval lies above zero)"
    return "these episodes do not separate its success by the two ways (the interval holds zero)"


def values() -> dict:
    res = json.loads(RESULTS.read_text())
    mach = json.loads(MACHINE.read_text())
    meta = json.loads((HERE / "data" / "metadata.json").read_text())
    evals = {n: json.loads((HERE / n / "eval.json").read_text()) for n in CLONES}
    configs = {n: read_yaml(HERE / n / "config.yaml") for n in CLONES}
    geo, st = res["geometry"], res["settings"]
    comp_table, comp = comparisons(res)
    refpo, wall = meta["refpo"], res["process_wall_s"]
    pre = {n: evals[n]["pretrain"] for n in CLONES}

    def secs(x: float | None) -> str:
        return "--" if x is None else f"{x:.0f} s"

    timing_rows = [
        "| step | in the process | the whole command (GNU time) |",
        "|---|---|---|",
        (
            f"| collection ({meta['total_episodes']} episodes) | {refpo['collect_time_s']:.1f} s (the rollouts) | "
            f"{secs(wall['collect'])} |"
        ),
    ]
    for n, lab in (("clone_flow", "flow clone"), ("clone_gauss", "Gaussian clone")):
        p = pre[n]
        timing_rows.append(
            f"| {lab} ({p['epochs_run']} epochs) | {p['time_s']:.0f} s (the training), "
            f"{evals[n]['eval_time_s']:.0f} s (its evaluation) | {secs(wall[n])} |"
        )
    label = {k: lab for k, _, lab in SETTINGS}
    timing_rows.append(
        f"| this page's rollouts ({res['episodes_per_clone_setting']} episodes a setting) | "
        + "; ".join(f"{label[k]}: {v:.0f} s" for k, v in res["rollout_s"].items())
        + " | -- |"
    )
    own = []
    for n, lab in (("clone_flow", "flow clone"), ("clone_gauss", "Gaussian clone")):
        for setting, r in evals[n]["results"].items():
            name = "its mean action" if setting == "mean_action" else setting.replace("N=", "N = ")
            own.append(f"{lab}, {name}: {r['return_mean']:.0f} ({r['episodes']} episodes)")

    def share(key: str, k: str, of: tuple[str, str] | None = None) -> str:
        s = st[key]
        n = s["episodes"] if of is None else s[of[0]] + s[of[1]]
        return f"{100 * s[k] / n:.0f} %"

    gm, gs = st["gauss_mean"], st["gauss_sample"]
    flow_pre, gauss_pre = pre["clone_flow"], pre["clone_gauss"]
    cap = configs["clone_flow"]["pretrain"]["epochs"]
    flow_stop = (
        f"ran all {flow_pre['epochs_run']} epochs of the cap (`pretrain.epochs={cap}`), its best validation loss at "
        f"epoch {flow_pre['best_epoch']}: its loss was still falling when it stopped"
        if not flow_pre["stopped_early"]
        else f"stopped early after {flow_pre['epochs_run']} epochs (best at epoch {flow_pre['best_epoch']})"
    )
    gauss_stop = (
        f"stopped early after {gauss_pre['epochs_run']} epochs (best at epoch {gauss_pre['best_epoch']})"
        if gauss_pre["stopped_early"]
        else f"ran all {gauss_pre['epochs_run']} epochs (best at epoch {gauss_pre['best_epoch']})"
    )
    both = lambda key: st[key]["left"] > 0 and st[key]["right"] > 0  # noqa: E731
    ways = lambda key: "both ways" if both(key) else "one way only"  # noqa: E731
    return {
        "episodes": meta["total_episodes"],
        "horizon": geo["horizon"],
        "seeds": ", ".join(sorted({str(configs[n]["seed"]) for n in CLONES})),
        "left_share": refpo["policy"]["left_share"],
        "data_left": pct(st["data"]["left"], st["data"]["episodes"]),
        "data_success": pct(st["data"]["success"], st["data"]["episodes"]),
        "data_seed": refpo["policy"]["seed"],
        "target_radius": geo["target_radius"],
        "target_x": geo["target_x"],
        "start_x": geo["start_x"],
        "spread": geo["start_spread"],
        "wall_t": geo["wall_half_thickness"],
        "wall_l": geo["wall_half_length"],
        "grown_a": f"{geo['grown_a']:.2f}",
        "grown_b": f"{geo['grown_b']:.2f}",
        "touch": WALL_TOUCH,
        "clone_episodes": res["episodes_per_clone_setting"],
        "measure_seed": res["measure_seed"],
        "batch_size": configs["clone_flow"]["pretrain"]["batch_size"],
        "hidden": " x ".join(str(h) for h in configs["clone_flow"]["actor"]["hidden_dims"]),
        "flow_stop": flow_stop,
        "flow_cap_note": (
            ""
            if flow_pre["stopped_early"]
            else " Its training stopped at the epoch cap with its validation loss still falling; whether longer "
            "training removes these failures was not measured."
        ),
        "gauss_stop": gauss_stop,
        "table": table(res),
        "failures": failures_table(res),
        "ways_table": ways_table(res),
        "comparisons": comp_table,
        "flow_success": share("flow_N10", "success"),
        "flow_ways": ways("flow_N10"),
        "flow_left_passes": share("flow_N10", "left", ("left", "right")),
        "flow_mix": mix_phrase(comp["left_flow_N10"]),
        "flow_vs_gm": success_phrase(comp["success_flow_N10_gauss_mean"], "the Gaussian clone's mean action"),
        "flow_vs_gs": success_phrase(comp["success_flow_N10_gauss_sample"], "its sampled actions"),
        "flow_vs_n1": success_phrase(comp["success_flow_N10_flow_N1"], "the same clone at N = 1"),
        "flow_fail": where_fail(st["flow_N10"]),
        "flow_by_way": way_phrase(comp["ways_flow_N10"]),
        "n1_success": share("flow_N1", "success"),
        "n1_fail": where_fail(st["flow_N1"]),
        "n1_by_way": way_phrase(comp["ways_flow_N1"]),
        "gm_wall_y": gm["failure_at_wall_abs_y"]["median"],
        "gm_wall_y_max": gm["failure_at_wall_abs_y"]["max"],
        "flow_far": st["flow_N10"]["failure_past_wall_distance_median"],
        "flow_fail_below": failed_below(st["flow_N10"], geo),
        "gs_fail": where_fail(gs),
        "n1_ways": ways("flow_N1"),
        "n1_mix": mix_phrase(comp["left_flow_N1"]),
        "gm_success": share("gauss_mean", "success"),
        "gm_none": share("gauss_mean", "none"),
        "gm_left_passes": share("gauss_mean", "left", ("left", "right")),
        "gm_mix": mix_phrase(comp["left_gauss_mean"]),
        "gm_fail": gm["episodes"] - gm["success"],
        "gm_at_wall": gm["failure_ends"]["at_wall"],
        "gm_back": gm["failure_ends"]["back_before_wall"],
        "gm_never": gm["failure_ends"]["never_passed"],
        "gm_loops": gm["failures_passed_more_than_once"],
        "flow_loops": st["flow_N10"]["failures_passed_more_than_once"],
        "gs_success": share("gauss_sample", "success"),
        "gs_left_passes": share("gauss_sample", "left", ("left", "right")),
        "gs_mix": mix_phrase(comp["left_gauss_sample"]),
        "own_eval": "; ".join(own),
        "timings": "\n".join(timing_rows),
        "cpu": mach["cpu_model"],
        "cores": mach["cpu_count"],
        "load": ", ".join(f"{x:g}" for x in mach["load_average_1_5_15"]),
        "versions": f"Python {mach['python']}, torch {mach['torch']}, Warp {mach['warp']}",
        "commit": mach["commit"],
        "keep_paths": KEEP_PATHS,
        "keep_failed": KEEP_FAILED,
        "every": EVERY,
    }


def main() -> None:
    from refpo_warp.studies.reports.results_page import main_args, write_page

    parser = main_args(__doc__.splitlines()[0])
    parser.add_argument("--measure", type=Path, metavar="RUNS_DIR", help="roll the clones of RUNS_DIR out first")
    args = parser.parse_args()
    if args.check and args.measure:
        parser.error("--check reads the committed files only: give it alone")
    if args.measure:
        measure(args.measure)
    if not args.check:
        res = json.loads(RESULTS.read_text())
        figure(res, FIGURE)
    same = write_page(TEMPLATE, values(), check=args.check)
    if args.check and not same:
        sys.exit(1)


if __name__ == "__main__":
    main()
