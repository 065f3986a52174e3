#!/usr/bin/env python
"""FPO++ at its authors' locomotion defaults, at its small-task recipe and at the tuned CPU values: ``README.md`` in
this folder, written whole from ``README.template.md`` and the values this script computes (nothing typed in by hand):

    python docs/results/fpo_pp/make_page.py [--add-runs runs/sweeps/cpu_fpo_pp] [--check]

What it reads (every seed each file holds):

- ``report/runs.csv``: one row per ``refpo sweep cpu_fpo_pp`` run (``refpo report``'s per-run rows), every label of
  ``configs/sweep/cpu_fpo_pp.yaml`` that has run. ``--add-runs`` appends the rows of a sweep dir's report
  (``<dir>/report/runs.csv``) for (task, label, seed) not yet in the file, and copies each run's ``config.yaml``,
  ``eval.json`` and periodic-evaluation rows to ``runs/<task>/<label>/seed<k>/``: that is how the small-task recipe's
  (``fpo_pp_small``) and the gradient-clip ablation's rows arrive. A failed run counts as return 0.
- ``runs/<task>/<label>/seed<k>/config.yaml`` and ``eval.json``: each setting's values and run sizes.
- ``report_task_profile/runs.csv``: the first grid (FPO++'s loss on the task's ReFPO profile).
- ``../tuning/fresh/runs.csv`` (label ``fpo_pp``) and ``../tuning/fresh/runs/``: FPO++ at the tuned CPU values.
- ``../cpu_dmc/runs.csv``: PPO, FPO and ReFPO at the paper's values.
- ``configs/sweep/cpu_fpo_pp.yaml`` (labels, names, the authors' values it pins), ``configs/task/_dmc.yaml`` (the
  values the CPU profile sets for fpo_pp), ``fpo_pp_reference.yaml`` (FPO++'s locomotion run sizes, with their
  places in FPO++'s code), ``../tuning/criteria.yaml`` (the N = 1 share the project tests) and ``gpu_h200/``.

Intervals: rliable's stratified bootstrap (``refpo_warp/studies/reports/intervals.py``: ``aggregate``'s mean and
``improvement``).
"""

from __future__ import annotations

import csv
import dataclasses
import json
import re
import statistics
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.reports.committed_runs import append_runs, seeds_text
from refpo_warp.studies.reports.intervals import Estimate, aggregate, improvement
from refpo_warp.studies.reports.results_page import main_args, write_page
from refpo_warp.utils.errors import DataFileError

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent
ROOT = RESULTS.parents[1]
REPORT = HERE / "report" / "runs.csv"
RUNS = HERE / "runs"
PROFILE = HERE / "report_task_profile" / "runs.csv"
TUNED = RESULTS / "tuning" / "fresh" / "runs.csv"
TUNED_RUNS = RESULTS / "tuning" / "fresh" / "runs"
CPU_DMC = RESULTS / "cpu_dmc" / "runs.csv"
SWEEP = ROOT / "configs" / "sweep" / "cpu_fpo_pp.yaml"
DMC_PROFILE = ROOT / "configs" / "task" / "_dmc.yaml"
REFERENCE = HERE / "fpo_pp_reference.yaml"
CRITERIA = RESULTS / "tuning" / "criteria.yaml"
GPU = HERE / "gpu_h200"
TASKS = ("dmc_cartpole_balance", "dmc_point_mass", "dmc_reacher_easy")
SMALL, AUTHORS, TUNED_KEY = "fpo_pp_small", "fpo_pp", "tuned"
CLIP_LABELS = ("fpo_pp_separate_clip", "fpo_pp_no_clip")
# setting -> (runs.csv column, the page's name for it); "headline" is FPO++'s own: N = 64 from zero initial noise.
SETTINGS = {
    "multi": ("return_multi", "N = 10"),
    "one": ("return_1", "N = 1"),
    "multi_zero": ("return_multi_zero", "N = 10, zero noise"),
    "headline": ("return_headline", "N = 64, zero noise"),
}
HEADLINE = "N=64/zero"
PROFILE_SUFFIX = "task profile, EMA from update 1"  # the first grid's rows (report_task_profile/)


def short(task: str) -> str:
    return task.removeprefix("dmc_")


# ------------------------------------------------------------------------------------------------ data
def read_rows(path: Path) -> list[dict]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


@dataclass(frozen=True)
class Method:
    key: str
    name: str
    csv: Path
    label: str
    source: str  # the file, as the page names it
    runs: Path | None = None  # the folder that holds <task>/<label>/seed<k>/config.yaml


def sweep_spec() -> dict:
    return load_yaml(SWEEP)


def methods() -> dict[str, Method]:
    """Every method the page shows, in the page's order: the three FPO++ settings first, then the others."""
    spec = sweep_spec()
    names = {m["label"]: m.get("name", m["label"]) for m in spec["methods"]}
    have = {r["label"] for r in read_rows(REPORT)}
    ordered = [m["label"] for m in spec["methods"] if m["label"] in have] + sorted(have - set(names))
    out = {}
    steps = authors_step_text()
    out[AUTHORS] = Method(
        AUTHORS,
        f"FPO++'s locomotion defaults at about {steps} % of their optimizer steps",
        REPORT,
        AUTHORS,
        "`report/runs.csv`",
        RUNS,
    )
    out[SMALL] = Method(SMALL, "FPO++'s small-task recipe", REPORT, SMALL, "`report/runs.csv`", RUNS)
    out[TUNED_KEY] = Method(
        TUNED_KEY, "FPO++ at the tuned CPU values", TUNED, "fpo_pp", "`../tuning/fresh/runs.csv`", TUNED_RUNS
    )
    for label, name in (("ppo", "PPO"), ("fpo", "FPO"), ("refpo", "ReFPO")):
        out[label] = Method(label, name, CPU_DMC, label, "`../cpu_dmc/runs.csv`")
    for label in ordered:
        if label not in out:
            out[label] = Method(label, names.get(label, label), REPORT, label, "`report/runs.csv`", RUNS)
    for label in sorted({r["label"] for r in read_rows(PROFILE)}, key=lambda x: (x != "fpo_pp", x != "refpo_pp", x)):
        name = names.get(label, label) + ", " + PROFILE_SUFFIX
        out[f"profile:{label}"] = Method(f"profile:{label}", name, PROFILE, label, "`report_task_profile/runs.csv`")
    return out


def finals(method: Method, setting: str) -> dict[str, dict[int, float]]:
    """task -> seed -> the final return at ``setting``; a failed run counts as 0 where the method has the setting."""
    column = SETTINGS[setting][0]
    out: dict[str, dict[int, float]] = {t: {} for t in TASKS}
    failed = []
    for row in read_rows(method.csv):
        if row["label"] != method.label or row["task"] not in out:
            continue
        if row["status"] == "failed":
            failed.append(row)
        elif row["status"] == "ok" and row.get(column):
            if setting == "headline" and row.get("headline") != HEADLINE:
                continue
            if setting.startswith("multi") and row.get("multi_step_n", "") not in ("", "10"):
                raise SystemExit(
                    f"{method.csv}: {row['task']}/{row['label']}/seed{row['seed']} has N = "
                    f"{row['multi_step_n']} in its multi-step column, where the page shows N = 10"
                )
            out[row["task"]][int(row["seed"])] = float(row[column])
    if any(out.values()):
        for row in failed:
            out[row["task"]][int(row["seed"])] = 0.0
    return {t: dict(sorted(seeds.items())) for t, seeds in out.items()}


def common_matrix(runs: dict[str, dict[int, float]]) -> np.ndarray | None:
    """(seeds x tasks) over the seeds every task has, or None where a task has none."""
    seeds = sorted(set.intersection(*(set(runs[t]) for t in TASKS)))
    return np.array([[runs[t][s] for t in TASKS] for s in seeds]) if seeds else None


# ------------------------------------------------------------------------------------------------ intervals
_CELLS: dict[tuple, str] = {}


def cell(values: dict[int, float]) -> str:
    """The mean over seeds (in seed order) with its 95 % interval; each score set is bootstrapped once."""
    if not values:
        return "--"
    key = tuple(values.values())
    if key not in _CELLS:
        e = aggregate({"m": np.array(key)[:, None]})["m"]["mean"]
        _CELLS[key] = e.text()
    return _CELLS[key]


def num(x: float) -> str:
    """A return in the page's prose: no decimals at 100 and above, one below."""
    return f"{x:.0f}" if abs(x) >= 100 else f"{x:.1f}"


def separates(p: Estimate) -> int:
    return 1 if p.low > 0.5 else -1 if p.high < 0.5 else 0


def short_verdict(p: Estimate, x: str, y: str) -> str:
    """What a probability of improvement's interval says about x against y: who is ahead, or neither."""
    side = separates(p)
    return f"{x} ahead" if side > 0 else f"{y} ahead" if side < 0 else "not separated (the interval holds 0.5)"


def poi(x: dict[str, dict[int, float]], y: dict[str, dict[int, float]], task: str | None) -> Estimate | None:
    """P(a run of x beats a run of y) on ``task`` (None: averaged over the three tasks, on the seeds each method has
    on all three), or None where either has no run there."""
    if task is None:
        mx, my = common_matrix(x), common_matrix(y)
        if mx is None or my is None:
            return None
        return improvement(mx, my)
    if not x[task] or not y[task]:
        return None
    return improvement(np.array(list(x[task].values()))[:, None], np.array(list(y[task].values()))[:, None])


# ------------------------------------------------------------------------------------------------ configs and sizes
def flat(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, dict) and v:
            out.update(flat(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def run_dirs(runs: Path | None, task: str, label: str) -> list[Path]:
    if runs is None:
        return []
    base = runs / task / label
    return sorted(p for p in base.glob("seed*") if (p / "config.yaml").exists()) if base.exists() else []


@dataclass(frozen=True)
class Size:
    envs: int
    steps: int
    iterations: int
    epochs: int
    minibatches: int

    @property
    def updates(self) -> int:
        return self.iterations * self.epochs * self.minibatches

    @property
    def minibatch(self) -> int:
        return self.envs * self.steps // self.minibatches


def run_size(run: Path) -> Size:
    cfg = load_yaml(run / "config.yaml")
    envs, steps = int(cfg["num_envs"]), int(cfg["runner"]["num_steps_per_env"])
    env_steps = json.loads((run / "eval.json").read_text())["env_steps"]
    return Size(
        envs,
        steps,
        env_steps // (envs * steps),
        int(cfg["algorithm"]["num_learning_epochs"]),
        int(cfg["algorithm"]["num_mini_batches"]),
    )


def sizes(method: Method) -> dict[str, Size]:
    """task -> the run size every committed run of the method on the task has (one, or an error)."""
    out = {}
    for task in TASKS:
        found = {run_size(r) for r in run_dirs(method.runs, task, method.label) if (r / "eval.json").exists()}
        if len(found) > 1:
            raise SystemExit(f"{method.key} on {task}: runs of different sizes {found}")
        if found:
            out[task] = found.pop()
    return out


def reference() -> dict:
    ref = load_yaml(REFERENCE)
    loco = {k: v["value"] for k, v in ref["locomotion"].items() if isinstance(v, dict)}
    return {"loco": loco, "robot": ref["locomotion"]["robot"], "ema_warmup": ref["ema"]["warmup_updates"]["value"]}


def loco_size() -> Size:
    loco = reference()["loco"]
    return Size(
        loco["num_envs"],
        loco["num_steps_per_env"],
        loco["max_iterations"],
        loco["num_learning_epochs"],
        loco["num_mini_batches"],
    )


def authors_sizes() -> dict[str, Size]:
    return sizes(Method(AUTHORS, "", REPORT, AUTHORS, "", RUNS))


def pct(x: float) -> str:
    return f"{100 * x:.1f} %"


def about(values: list[float]) -> str:
    """Percentages rounded to whole numbers: one, or the range they span."""
    rounded = sorted({round(100 * v) for v in values})
    return str(rounded[0]) if len(rounded) == 1 else f"{rounded[0]}-{rounded[-1]}"


def authors_step_text() -> str:
    loco = loco_size()
    return about([s.updates / loco.updates for s in authors_sizes().values()])


def fmt_value(v) -> str:
    if v is None:
        return "null"
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


KEPT_OUT = ("pretrain.", "video.", "eval.", "env.", "runner.save_interval", "runner.logger")
RUN_KEYS = {"task", "algo", "seed", "device", "run_dir", "resume", "verbose", "notice", "config_dir", "max_iterations"}


def run_config(method: Method, task: str) -> dict | None:
    """The method's config on the task (flattened, without what names the run); the same for every seed."""
    configs = []
    for run in run_dirs(method.runs, task, method.label):
        cfg = flat(load_yaml(run / "config.yaml"))
        configs.append({k: v for k, v in cfg.items() if k not in RUN_KEYS and not k.startswith(KEPT_OUT)})
    if not configs:
        return None
    if any(c != configs[0] for c in configs[1:]):
        raise SystemExit(f"{method.key} on {task}: seeds with different configs")
    return configs[0]


def values_table(ms: dict[str, Method]) -> tuple[str, list[str]]:
    """The values the three settings' runs differ in (as their config.yaml hold them), and the sizes each gives."""
    keys3 = (AUTHORS, SMALL, TUNED_KEY)
    configs = {k: {t: run_config(ms[k], t) for t in TASKS} for k in keys3}
    differ = set()
    for task in TASKS:
        present = [c for c in (configs[k][task] for k in keys3) if c is not None]
        for key in set().union(*present):
            if len({json.dumps(c.get(key, "(absent)"), sort_keys=True) for c in present}) > 1:
                differ.add(key)

    def cells(key: str) -> list[str]:
        out = []
        for k in keys3:
            vals = [c for c in (configs[k][t] for t in TASKS) if c is not None]
            if not vals:
                out.append("--")
                continue
            shown = list(dict.fromkeys(fmt_value(c[key]) if key in c else "(absent)" for c in vals))
            out.append(" / ".join(shown))
        return out

    head = "| value | locomotion defaults | small-task recipe | tuned CPU values |"
    lines = [head, "|---|---|---|---|"]
    for key in sorted(differ):
        lines.append(f"| `{key}` | " + " | ".join(cells(key)) + " |")
    size_cells, mb_cells = [], []
    for k in keys3:
        s = sizes(ms[k])
        size_cells.append(" / ".join(f"{s[t].updates:,}" for t in TASKS if t in s) or "--")
        mb_cells.append(" / ".join(f"{s[t].minibatch:,}" for t in TASKS if t in s) or "--")
    order = " / ".join(short(t) for t in TASKS)
    lines.append(f"| optimizer steps a run ({order}) | " + " | ".join(size_cells) + " |")
    lines.append(f"| transitions a minibatch ({order}) | " + " | ".join(mb_cells) + " |")
    missing = [ms[k].name for k in keys3 if all(configs[k][t] is None for t in TASKS)]
    return "\n".join(lines), missing


# ------------------------------------------------------------------------------------------------ tables
def settings_table(ms: dict[str, Method], data: dict) -> str:
    lines = [
        "| task | FPO++ at | seeds | N = 10 | N = 1 | N = 64, zero noise |",
        "|---|---|---|---|---|---|",
    ]
    for task in TASKS:
        for key in (AUTHORS, SMALL, TUNED_KEY):
            runs = data[key]
            seeds = set().union(*(set(runs[s][task]) for s in ("multi", "one", "headline")))
            cells = [cell(runs[s][task]) for s in ("multi", "one", "headline")]
            lines.append(
                f"| {short(task)} | {ms[key].name} | {seeds_text(seeds) if seeds else 'no runs yet'} | "
                + " | ".join(cells)
                + " |"
            )
    return "\n".join(lines)


def all_table(ms: dict[str, Method], data: dict) -> str:
    lines = [
        "| task | method | seeds | N = 10 | N = 1 | N = 10, zero noise | N = 64, zero noise | file |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for task in TASKS:
        for key, m in ms.items():
            runs = data[key]
            seeds = set().union(*(set(runs[s][task]) for s in SETTINGS))
            if not seeds:
                continue
            cells = [cell(runs[s][task]) for s in SETTINGS]
            lines.append(
                f"| {short(task)} | {m.name} | {seeds_text(seeds)} | " + " | ".join(cells) + f" | {m.source} |"
            )
    return "\n".join(lines)


def poi_rows(pairs, ms, data, settings=("multi", "headline")) -> tuple[list[str], list[tuple]]:
    """Table rows for each (x over y) pair, per task and over the three tasks; and (x, y, task, setting, p) kept."""
    rows, kept = [], []
    for x, y, label in pairs:
        for task in (*TASKS, None):
            ps = {s: poi(data[x][s], data[y][s], task) for s in settings}
            if all(p is None for p in ps.values()):
                continue
            where = short(task) if task else "the three tasks"
            if task is not None and min(len(data[x][settings[0]][task]), len(data[y][settings[0]][task])) < 2:
                # one seed's bootstrap is that seed: its interval is a point, whatever the runs are
                dashes = " | ".join("--" for _ in settings)
                rows.append(f"| {where} | {label[0]} over {label[1]} | {dashes} | one seed on a side: not compared |")
                continue
            cells = []
            for s in settings:
                p = ps[s]
                cells.append("--" if p is None else f"{p.text(2)}")
                if p is not None:
                    kept.append((x, y, task, s, p))
            says = "; ".join(
                f"{SETTINGS[s][1]}: {short_verdict(p, *label)}" for s in settings if (p := ps[s]) is not None
            )
            rows.append(f"| {where} | {label[0]} over {label[1]} | " + " | ".join(cells) + f" | {says} |")
    return rows, kept


def poi_table(rows: list[str], settings=("multi", "headline")) -> str:
    head = "| where | comparison | " + " | ".join(f"P(improvement) [95 %], {SETTINGS[s][1]}" for s in settings)
    return "\n".join([head + " | what it says |", "|---|---|" + "---|" * len(settings) + "---|", *rows])


def small_verdicts(kept: list[tuple], ms: dict[str, Method]) -> str:
    """One sentence per comparison of the small recipe: where its runs beat, lose, or the seeds do not separate."""
    out = []
    shown = {AUTHORS: "the locomotion defaults", TUNED_KEY: "the tuned values"}
    for y in (AUTHORS, TUNED_KEY):
        parts = []
        for s in ("multi", "headline"):
            got = {task: p for x_, y_, task, s_, p in kept if x_ == SMALL and y_ == y and s_ == s}
            if not got:
                continue
            groups: dict[int, list[str]] = {1: [], -1: [], 0: []}
            for task, p in got.items():
                groups[separates(p)].append("over the three tasks" if task is None else f"on {short(task)}")
            bits = []
            if groups[1]:
                bits.append("its runs beat them " + ", ".join(groups[1]))
            if groups[-1]:
                bits.append("theirs beat it " + ", ".join(groups[-1]))
            if groups[0]:
                bits.append("the seeds do not separate them " + ", ".join(groups[0]))
            parts.append(f"at {SETTINGS[s][1]}, " + "; ".join(bits))
        if parts:
            out.append(f"- **The small-task recipe against {shown[y]}**: " + "; ".join(parts) + ".")
    return "\n".join(out)


# ------------------------------------------------------------------------------------------------ adding runs
def add_runs(sweep_dir: Path) -> None:
    """Append the sweep's new (task, label, seed) rows to report/runs.csv, copying their small files under runs/."""
    added = append_runs(sweep_dir, REPORT, RUNS, ROOT)
    print(f"{REPORT.relative_to(ROOT)}: {added} run(s) added from {sweep_dir}")


# ------------------------------------------------------------------------------------------------ the page's parts
def sweep_text(ms: dict[str, Method]) -> dict[str, str]:
    """What configs/sweep/cpu_fpo_pp.yaml does now, checked against the CPU profile and the committed runs."""
    spec = sweep_spec()
    by_label = {m["label"]: m for m in spec["methods"]}
    authors = dict(by_label[AUTHORS].get("overrides") or {})
    on_authors, own = [], []
    for label, m in by_label.items():
        over = m.get("overrides") or {}
        if not all(k in over for k in authors):
            own.append(f"`{label}`")
            continue
        text = f"`{label}`"
        changed = [f"`{k}: {fmt_value(over[k])}`" for k in authors if over[k] != authors[k]]
        extra = [f"`{k}: {fmt_value(x)}`" for k, x in over.items() if k not in authors]
        if changed:
            text += " but " + ", ".join(changed)
        if extra:
            text += " plus " + ", ".join(extra)
        on_authors.append(text)
    profile = flat(load_yaml(DMC_PROFILE)["by_device"]["cpu"]["by_algo"][AUTHORS])
    same_keys = set(profile) == set(authors)
    held = []
    for task in TASKS:
        cfg = run_config(ms[AUTHORS], task)
        if cfg is not None:
            held.append(all(cfg.get(k) == v for k, v in authors.items()))
    tuned = {}
    for task in TASKS:
        cfg = run_config(ms[TUNED_KEY], task)
        if cfg is not None:
            tuned = cfg
            break
    tuned_match = all(tuned.get(k) == v for k, v in profile.items())
    return {
        "pinned_values": ", ".join(f"`{k}: {fmt_value(v)}`" for k, v in authors.items()),
        "profile_values": ", ".join(f"`{k}: {fmt_value(v)}`" for k, v in profile.items()),
        "profile_keys_note": (
            "the same keys" if same_keys else f"keys {sorted(set(profile) ^ set(authors))} differ between the two"
        ),
        "on_authors": "; ".join(on_authors),
        "own_labels": ", ".join(own) if own else "none",
        "runs_hold": (
            "the committed `fpo_pp` runs' `config.yaml` hold the pinned values"
            if held and all(held)
            else "the committed `fpo_pp` runs' `config.yaml` do not all hold the pinned values"
        ),
        "tuned_hold": (
            "the tuned runs' `config.yaml` hold the profile's values"
            if tuned and tuned_match
            else "the tuned runs' `config.yaml` do not hold the profile's values"
        ),
    }


def what_ran() -> tuple[str, str]:
    """Per label of report/runs.csv: tasks, seeds, runs; and the labels of the sweep file with no row yet."""
    rows = read_rows(REPORT)
    spec = sweep_spec()
    parts = []
    for m in spec["methods"]:
        mine = [r for r in rows if r["label"] == m["label"]]
        if not mine:
            continue
        tasks = sorted({r["task"] for r in mine}, key=TASKS.index)
        seeds = sorted({int(r["seed"]) for r in mine})
        where = "the three tasks" if len(tasks) == len(TASKS) else ", ".join(short(t) for t in tasks)
        failed = sum(r["status"] == "failed" for r in mine)
        parts.append(
            f"`{m['label']}` on {where}, seed{'s' if len(seeds) > 1 else ''} {seeds_text(seeds)} "
            f"({len(mine)} run{'s' if len(mine) > 1 else ''}" + (f", {failed} failed" if failed else "") + ")"
        )
    missing = [f"`{m['label']}`" for m in spec["methods"] if not any(r["label"] == m["label"] for r in rows)]
    return "; ".join(parts), (", ".join(missing) if missing else "none")


def gpu_values() -> dict[str, str]:
    """The GPU call's figures (gpu_h200/), and the two configs' sampling and update sizes."""
    from refpo_warp.algorithms.refpo import ReFPO
    from refpo_warp.models.flow_actor import FlowActor
    from refpo_warp.utils.options import option_fields

    script = (GPU / "run.sh").read_text()
    limits = dict(re.findall(r'"(\w+) (\d+)"', script))
    summary = dict(re.findall(r"^(\w+) rc=(\d+)", (GPU / "summary.txt").read_text(), re.MULTILINE))
    found = re.search(r"max_iterations=(\d+)", script)
    if found is None:
        raise DataFileError(f"{GPU / 'run.sh'}: no max_iterations=<n> (the iterations the GPU job requested)")
    requested = found.group(1)
    head = "| algo | iterations | env steps | training time | env steps / s (median iteration) | last training return |"
    table = [head, "|---|---|---|---|---|---|"]
    rate, cfg = {}, {}
    for algo in ("fpo_pp", "refpo"):
        rows = [json.loads(line) for line in (GPU / f"{algo}_progress.jsonl").read_text().splitlines() if line]
        cfg[algo] = load_yaml(GPU / f"{algo}_config.yaml")
        last = rows[-1]
        rate[algo] = last["env_steps"] / last["time_s"]
        median = statistics.median(r["steps_per_s"] for r in rows)
        table.append(
            f"| `{algo}` | {len(rows)} ({rows[0]['iteration']}..{last['iteration']}) | {last['env_steps']:,} | "
            f"{last['time_s']:.0f} s | {rate[algo]:,.0f} ({median:,.0f}) | {last['reward_mean']:.0f} |"
        )
    actor_default = {f.name: f.default for f in dataclasses.fields(FlowActor.Options)}["num_flow_steps"]
    pairs_default = option_fields(ReFPO)["num_mc_samples"].default
    fp, rf = cfg["fpo_pp"], cfg["refpo"]
    n_fp = len([line for line in (GPU / "fpo_pp_progress.jsonl").read_text().splitlines() if line])
    gpu_name = (GPU / "gpu.txt").read_text().splitlines()[1].split(",")[0].strip()
    return {
        "gpu_name": gpu_name,
        "gpu_envs": f"{fp['num_envs']:,}",
        "gpu_steps": f"{fp['runner']['num_steps_per_env']:,}",
        "gpu_iteration_steps": f"{fp['num_envs'] * fp['runner']['num_steps_per_env']:,}",
        "gpu_requested": requested,
        "gpu_table": "\n".join(table),
        "gpu_rate_ratio": f"{rate['fpo_pp'] / rate['refpo']:.2f}",
        "gpu_fp_flow": str(fp["actor"].get("num_flow_steps", actor_default)),
        "gpu_rf_flow": str(rf["actor"].get("num_flow_steps", actor_default)),
        "gpu_fp_pairs": str(fp["algorithm"].get("num_mc_samples", pairs_default)),
        "gpu_rf_pairs": str(rf["algorithm"].get("num_mc_samples", pairs_default)),
        "gpu_fp_epochs": str(fp["algorithm"]["num_learning_epochs"]),
        "gpu_rf_epochs": str(rf["algorithm"]["num_learning_epochs"]),
        "gpu_limit": limits["fpo_pp"],
        "gpu_fp_rc": summary.get("fpo_pp", "?"),
        "gpu_fp_done": str(n_fp),
    }


def pairs_by_seed(a: dict[str, dict[int, float]], b: dict[str, dict[int, float]]):
    """(task, seed, a, b) for every (task, seed) both have."""
    return [(t, s, a[t][s], b[t][s]) for t in TASKS for s in sorted(set(a[t]) & set(b[t]))]


def findings(ms: dict[str, Method], data: dict) -> dict[str, str]:
    out = {}
    au = data[AUTHORS]
    # Against PPO, FPO and ReFPO, seed by seed.
    below = []
    for key in ("ppo", "fpo", "refpo"):
        pairs = pairs_by_seed(au["multi"], data[key]["multi"])
        n_below = sum(x < y for _, _, x, y in pairs)
        text = f"{ms[key].name}'s in {n_below} of {len(pairs)}"
        exceptions = [
            f"{short(t)} seed {s}, {ms[key].name} {num(y)} against FPO++ {num(x)}" for t, s, x, y in pairs if x >= y
        ]
        if exceptions:
            text += f" (not below: {'; '.join(exceptions)})"
        below.append(text)
    out["vs_others"] = ", ".join(below)
    means = {k: {t: np.mean(list(data[k]["multi"][t].values())) for t in TASKS if data[k]["multi"][t]} for k in data}
    out["authors_means"] = ", ".join(f"{num(means[AUTHORS][t])} on {short(t)}" for t in TASKS)
    out["authors_headline"] = ", ".join(
        num(np.mean(list(au["headline"][t].values()))) for t in TASKS if au["headline"][t]
    )
    for key in ("ppo", "refpo"):
        out[f"{key}_means"] = ", ".join(num(means[key][t]) for t in TASKS)
    pm = "dmc_point_mass"
    out["pm_seeds"] = " / ".join(num(au["multi"][pm][s]) for s in sorted(au["multi"][pm]))
    # ReFPO on FPO++ against FPO++.
    pairs = pairs_by_seed(data["refpo_pp"]["multi"], au["multi"])
    gap = max(pairs, key=lambda p: abs(p[2] - p[3]))
    out["reflow_max_gap"] = f"{abs(gap[2] - gap[3]):.1f}"
    out["reflow_gap_where"] = f"{short(gap[0])} seed {gap[1]}, ReFPO on FPO++ {num(gap[2])} against FPO++ {num(gap[3])}"
    out["reflow_pairs"] = str(len(pairs))
    # Zero noise against random noise, run by run; the headline N = 64 against N = 10, both from zero noise.
    zero, head = [], []
    for t in TASKS:
        p = [
            (s, au["multi_zero"][t][s], au["multi"][t][s])
            for s in sorted(set(au["multi_zero"][t]) & set(au["multi"][t]))
        ]
        zero.append(
            f"{short(t)} {num(np.mean([r for _, _, r in p]))} → {num(np.mean([z for _, z, _ in p]))}, higher in "
            f"{sum(z > r for _, z, r in p)} of {len(p)} runs"
        )
        h = [
            (s, au["headline"][t][s], au["multi_zero"][t][s])
            for s in sorted(set(au["headline"][t]) & set(au["multi_zero"][t]))
        ]
        head.append(
            f"{short(t)} {num(np.mean([a for _, a, _ in h]))} against {num(np.mean([b for _, _, b in h]))}, higher in "
            f"{sum(a > b for _, a, b in h)} of {len(h)} runs"
        )
    out["zero_noise"] = "; ".join(zero)
    out["headline_vs_ten"] = "; ".join(head)
    # The flow's straightness and the one-step share, from report/runs.csv.
    share = load_yaml(CRITERIA)["goal"]["one_step"]["share"]
    rows = [r for r in read_rows(REPORT) if r["status"] == "ok"]
    err = {}
    for label in (AUTHORS, "refpo_pp"):
        for t in TASKS:
            vals = [float(r["one_step"]) for r in rows if r["label"] == label and r["task"] == t and r["one_step"]]
            if vals:
                err[(label, t)] = float(np.mean(vals))
    out["one_step_low"] = f"{min(err.values()):.1e}"
    out["one_step_high"] = f"{max(err.values()):.1e}"
    out["share"] = str(share)
    held, counts = 0, []
    for t in TASKS:
        runs = [r for r in rows if r["label"] == AUTHORS and r["task"] == t]
        k = sum(float(r["return_1"]) >= share * float(r["return_multi"]) for r in runs)
        held += k
        counts.append(f"{short(t)} {k}/{len(runs)}")
    out["share_held"] = f"{held} of {sum(r['label'] == AUTHORS for r in rows)}"
    out["share_counts"] = ", ".join(counts)
    straight = [float(r["straightness"]) for r in rows if r["label"] in (AUTHORS, "refpo_pp") and r["straightness"]]
    out["straight_range"] = f"{min(straight):.2f} to {max(straight):.2f}"
    # Run health by FPO++'s rule.
    from refpo_warp.evaluation.run_health import MIN_PLATEAU, WINDOW

    health: dict[str, int] = {}
    for r in rows:
        health[r["health"]] = health.get(r["health"], 0) + 1
    out["health"] = ", ".join(f"{n} `{h}`" for h, n in sorted(health.items()))
    out["health_runs"] = str(len(rows))
    out["health_needs"] = str(MIN_PLATEAU + WINDOW)
    return out


def lr_text(data: dict, ms: dict[str, Method]) -> str:
    """FPO++ at learning rate 3e-4 against its own, on the tasks it ran."""
    key = "fpo_pp_lr3e-4"
    if key not in data:
        return "not run"
    lr, au, prof = data[key], data[AUTHORS], data.get("profile:fpo_pp")
    parts = []
    for t in TASKS:
        if not lr["multi"][t]:
            continue
        p = poi(lr["multi"], au["multi"], t)
        if p is None:  # no run at its own rate on t
            continue
        seeds = sorted(set(lr["multi"][t]) & set(au["multi"][t]))
        higher = sum(lr["multi"][t][s] > au["multi"][t][s] for s in seeds)
        text = (
            f"on {short(t)} its N = 10 return is {cell(lr['multi'][t])} against {cell(au['multi'][t])}, higher in "
            f"{higher} of {len(seeds)} seeds ({' / '.join(num(lr['multi'][t][s]) for s in seeds)} against "
            f"{' / '.join(num(au['multi'][t][s]) for s in seeds)}; P(improvement) "
            f"{p.text(2)}: {short_verdict(p, 'the higher rate', 'its own')})"
        )
        if lr["headline"][t] and au["headline"][t]:
            text += f", and its N = 64 zero-noise return {cell(lr['headline'][t])} against {cell(au['headline'][t])}"
        q = poi(prof["multi"], lr["multi"], t) if prof is not None else None
        if q is not None and prof is not None:
            text += (
                f"; the first grid's FPO++ reached {cell(prof['multi'][t])} at N = 10 (P(a first-grid run beats one at "
                f"the higher rate) {q.text(2)}: "
                f"{short_verdict(q, 'the first grid', 'the higher rate')})"
            )
        parts.append(text)
    return "; ".join(parts)


def clip_text(data: dict, ms: dict[str, Method]) -> str:
    present = [label for label in CLIP_LABELS if label in data and any(data[label]["multi"].values())]
    if not present:
        return (
            "Not run yet: `report/runs.csv` has no row of "
            + " or ".join(f"`{label}`" for label in CLIP_LABELS)
            + ". The rows and their comparison with the joint clip appear here when they do."
        )
    pm = "dmc_point_mass"
    means = ["| FPO++ at the authors' values, with | seeds | N = 10 | N = 64, zero noise |", "|---|---|---|---|"]
    for key, name in ((AUTHORS, "the joint clip"), *((label, ms[label].name) for label in present)):
        runs = data[key]
        seeds = set(runs["multi"][pm]) | set(runs["headline"][pm])
        means.append(f"| {name} | {seeds_text(seeds)} | {cell(runs['multi'][pm])} | {cell(runs['headline'][pm])} |")
    rows, _ = poi_rows([(label, AUTHORS, (ms[label].name, "the joint clip")) for label in present], ms, data)
    return "\n".join(means) + "\n\n" + poi_table(rows)


# ------------------------------------------------------------------------------------------------ the page
def values() -> dict[str, object]:
    ms = methods()
    data = {key: {s: finals(m, s) for s in SETTINGS} for key, m in ms.items()}
    small_present = any(data[SMALL]["multi"].values())
    v: dict[str, object] = {}

    # Sizes: ours at the authors' values against FPO++'s locomotion runs.
    loco, ref = loco_size(), reference()
    ours = authors_sizes()
    v["loco_robot"] = ref["robot"]
    v["loco_envs"] = f"{loco.envs:,}"
    v["loco_steps"] = str(loco.steps)
    v["loco_iterations"] = f"{loco.iterations:,}"
    v["loco_epochs"] = str(loco.epochs)
    v["loco_minibatches"] = str(loco.minibatches)
    v["loco_updates"] = f"{loco.updates:,}"
    v["loco_minibatch"] = f"{loco.minibatch:,}"
    v["our_sizes"] = "; ".join(
        f"{short(t)} {s.iterations} iterations × {s.epochs} epochs × {s.minibatches} minibatches = {s.updates:,} "
        f"({pct(s.updates / loco.updates)}) in minibatches of {s.envs} × {s.steps} / {s.minibatches} = "
        f"{s.minibatch:,} transitions ({pct(s.minibatch / loco.minibatch)})"
        for t, s in ours.items()
    )
    v["step_about"] = authors_step_text()
    v["mb_about"] = about([s.minibatch / loco.minibatch for s in ours.values()])
    iters = sorted({s.iterations for s in ours.values()})
    v["our_iterations"] = "-".join(str(i) for i in (iters[0], iters[-1])) if len(iters) > 1 else str(iters[0])
    envs = sorted({s.envs for s in ours.values()})
    v["our_envs"] = "-".join(str(e) for e in (envs[0], envs[-1])) if len(envs) > 1 else str(envs[0])
    from refpo_warp.algorithms.on_policy import OnPolicyAlgorithm
    from refpo_warp.utils.options import option_fields

    v["ema_warmup"] = str(ref["ema_warmup"])
    v["ema_ours"] = (
        "and so does ours (`ema_warmup`, `refpo_warp/algorithms/on_policy.py`)"
        if option_fields(OnPolicyAlgorithm)["ema_warmup"].default == ref["ema_warmup"]
        else "ours starts at another count (`ema_warmup`, `refpo_warp/algorithms/on_policy.py`)"
    )
    v["ema_live"] = (
        "so every run here is evaluated on its live weights, as FPO++'s would be at this length"
        if max(s.iterations for s in ours.values()) < ref["ema_warmup"]
        else "so the longer runs here are evaluated on their average"
    )

    v["profile_suffix"] = PROFILE_SUFFIX
    v.update(sweep_text(ms))
    v["authors_name"] = ms[AUTHORS].name
    table, missing = values_table(ms)
    v["values_table"] = table
    v["values_missing"] = "Columns without a committed run show `--`: " + ", ".join(missing) + "." if missing else ""
    v["settings_table"] = settings_table(ms, data)

    # The small recipe against the other two settings, and the tuned values against the authors'.
    if small_present:
        pairs = [
            (SMALL, AUTHORS, ("the small-task recipe", "the locomotion defaults")),
            (SMALL, TUNED_KEY, ("the small-task recipe", "the tuned values")),
            (TUNED_KEY, AUTHORS, ("the tuned values", "the locomotion defaults")),
        ]
    else:
        pairs = [(TUNED_KEY, AUTHORS, ("the tuned values", "the locomotion defaults"))]
    rows, kept = poi_rows(pairs, ms, data)
    v["small_poi_table"] = poi_table(rows)
    v["small_verdicts"] = (
        small_verdicts(kept, ms)
        if small_present
        else "- **The small-task recipe**: no committed run yet (`report/runs.csv` has no `fpo_pp_small` row); its "
        "rows, and its probabilities of improvement over the locomotion defaults and over the tuned values, appear "
        "here when they do."
    )
    tuned_groups: dict[int, list[str]] = {1: [], -1: [], 0: []}
    for x, y, task, s, p in kept:
        if x == TUNED_KEY and y == AUTHORS and s == "multi":
            tuned_groups[separates(p)].append("over the three tasks" if task is None else f"on {short(task)}")
    bits = []
    if tuned_groups[1]:
        bits.append("its runs beat the locomotion defaults' " + ", ".join(tuned_groups[1]))
    if tuned_groups[-1]:
        bits.append("the locomotion defaults' beat them " + ", ".join(tuned_groups[-1]))
    if tuned_groups[0]:
        bits.append("the seeds do not separate them " + ", ".join(tuned_groups[0]))
    v["tuned_verdict"] = "; ".join(bits)

    # The other comparisons.
    other = [
        (key, AUTHORS, (ms[key].name, "the locomotion defaults"))
        for key, m in ms.items()
        if m.csv == REPORT and key not in (AUTHORS, SMALL, *CLIP_LABELS)
    ]
    if "profile:fpo_pp" in data:
        other.append(("profile:fpo_pp", AUTHORS, ("the first grid's FPO++", "the locomotion defaults")))
    for label in ("profile:fpo_pp_mean_ratio", "profile:fpo_pp_ppo_clip"):
        if label in data:
            other.append(
                (label, "profile:fpo_pp", (ms[label].name.split(", " + PROFILE_SUFFIX)[0], "the first grid's FPO++"))
            )
    rows, kept_other = poi_rows(other, ms, data)
    v["other_poi_table"] = poi_table(rows)
    reflow = [p for x, _, _, _, p in kept_other if x == "refpo_pp"]
    v["reflow_separate"] = (
        "no task and no setting in which the seeds separate them"
        if reflow and not any(separates(p) for p in reflow)
        else f"the seeds separate them in {sum(bool(separates(p)) for p in reflow)} of {len(reflow)} cases"
    )
    spec = {m["label"]: m for m in sweep_spec()["methods"]}
    authors = spec[AUTHORS].get("overrides") or {}
    v["clip_setup"] = "; ".join(
        f"`{label}` sets "
        + ", ".join(
            f"`{k}: {fmt_value(x)}`" for k, x in (spec[label].get("overrides") or {}).items() if k not in authors
        )
        for label in CLIP_LABELS
        if label in spec
    )
    v["joint_clip"] = ", ".join(
        f"`{k}: {fmt_value(x)}`"
        for k, x in (run_config(ms[AUTHORS], TASKS[1]) or {}).items()
        if k in ("algorithm.max_grad_norm", "algorithm.joint_grad_clip")
    )
    ran_ablation = [k for k in ("fpo_pp_mean_ratio", "fpo_pp_ppo_clip") if k in data and any(data[k]["multi"].values())]
    v["ablation_authors_state"] = (
        "have run: rows " + ", ".join(f"`{k}`" for k in ran_ablation) + " in the tables above"
        if ran_ablation
        else "have not run: `report/runs.csv` has no `fpo_pp_mean_ratio` or `fpo_pp_ppo_clip` row"
    )
    every = {run_size(r).iterations for r in RUNS.glob("*/*/seed*") if (r / "eval.json").exists()}
    v["all_iterations"] = f"{min(every)}-{max(every)}" if len(every) > 1 else str(min(every))
    proto = load_yaml(run_dirs(RUNS, TASKS[0], AUTHORS)[0] / "config.yaml")["eval"]
    v["eval_protocol"] = (
        ", ".join(f"N = {n}" for n in proto["flow_steps"])
        + ", each from "
        + " and from ".join(f"{x} initial noise" for x in proto["initial_noise"])
    )
    v["all_table"] = all_table(ms, data)

    v.update(findings(ms, data))
    v["lr_text"] = lr_text(data, ms)
    v["clip_text"] = clip_text(data, ms)
    ran, missing_labels = what_ran()
    v["what_ran"] = ran
    v["not_run"] = missing_labels
    # The first grid: its ablation against its own FPO++, seed by seed.
    prof = []
    pm = "dmc_point_mass"
    base = data.get("profile:fpo_pp")
    for label in ("profile:fpo_pp_mean_ratio", "profile:fpo_pp_ppo_clip"):
        if label not in data or base is None:
            continue
        seeds = sorted(set(data[label]["multi"][pm]) & set(base["multi"][pm]))
        higher = sum(data[label]["multi"][pm][s] > base["multi"][pm][s] for s in seeds)
        name = ms[label].name.split(", " + PROFILE_SUFFIX)[0]
        prof.append(f"{name}: {cell(data[label]['multi'][pm])}, higher in {higher} of {len(seeds)} seeds")
    v["profile_ablation"] = "; ".join(prof)
    v["profile_fpo_pm"] = cell(base["multi"][pm]) if base else "--"
    v["profile_vs_authors"] = (
        "; ".join(f"{short(t)} {cell(base['multi'][t])} against {cell(data[AUTHORS]['multi'][t])}" for t in TASKS)
        if base
        else "--"
    )
    v.update(gpu_values())
    return v


def main() -> None:
    parser = main_args(__doc__.splitlines()[0])
    parser.add_argument("--add-runs", nargs="*", default=[], type=Path, help="sweep dirs whose new runs to add")
    args = parser.parse_args()
    for sweep_dir in args.add_runs:
        add_runs(sweep_dir)
    same = write_page(HERE / "README.template.md", values(), check=args.check)
    sys.exit(0 if same or not args.check else 1)


if __name__ == "__main__":
    main()
