"""The FPO++ page's data: its files and settings, the methods it shows, their runs' final returns, configs and sizes,
and rliable's intervals over them (``make_page.py`` writes the page)."""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.grid.spec import computed_part
from refpo_warp.studies.reports.intervals import Estimate, improvement, improvement_of, mean_estimate

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent
ROOT = RESULTS.parents[1]
REPORT = HERE / "report" / "runs.csv"
# Where the runs made before eval.json recorded its machine ran: the sessions' machines, one torch thread a run
UNRECORDED_MACHINE = "machines the runs did not record (2-core CPUs, one torch thread a run: `../history.md`)"
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
def cell(values: dict[int, float]) -> str:
    """The mean over seeds (in seed order) with its 95 % interval."""
    return mean_estimate(values.values()).text() if values else "--"


def num(x: float) -> str:
    """A return in the page's prose: no decimals at 100 and above, one below."""
    return f"{x:.0f}" if abs(x) >= 100 else f"{x:.1f}"


def short_verdict(p: Estimate, x: str, y: str) -> str:
    """What a probability of improvement's interval says about x against y: who is ahead, or neither."""
    side = p.side
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
    return improvement_of(x[task].values(), y[task].values())


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
    """The method's config on the task (flattened, without what names the run and the options that do not change
    what it computes, so runs saved before such an option existed compare equal); the same for every seed."""
    configs = []
    for run in run_dirs(method.runs, task, method.label):
        cfg = flat(computed_part(load_yaml(run / "config.yaml")))
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
