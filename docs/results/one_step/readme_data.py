"""What one_step/README.md reads, gathered once for the page's sections (readme_summary.py, readme_details.py):
one_step.json, report/runs.csv, ../cpu_dmc/runs.csv, configs/sweep/cpu_reflow_pairs.yaml and criteria.yaml; and the
methods' names, the variants' roles and the number format the sections share."""

import json
from pathlib import Path
from types import SimpleNamespace

import run_rows as st
from intervention import VARIANTS

from refpo_warp.utils.errors import DataFileError

HERE = Path(__file__).resolve().parent
PAGE_METHODS = ("fpo", "refpo", "refpo_coupled", "refpo_adaptive")  # the sweep's labels, in the table's order
REFPO_VARIANTS = ("refpo", "refpo_coupled", "refpo_adaptive")
SHORT = {
    "fpo": "FPO",
    "refpo": "independent pairs",
    "refpo_coupled": "coupled pairs",
    "refpo_adaptive": "the adaptive λ",
}


def diag(x: float) -> str:
    """A diagnostic for the prose: three decimals, or two significant digits below 0.001."""
    if x == 0:
        return "0"
    return f"{x:.2g}" if abs(x) < 0.001 else f"{x:.3f}" if abs(x) < 1 else f"{x:.2f}"


def variant_roles(variants: dict) -> dict[str, str]:
    """The intervention's variants by what they change (VARIANTS' overrides), so the page names each by role."""
    roles = {}
    for name, change in VARIANTS.items():
        if name not in variants:
            raise DataFileError(f"one_step.json's intervention has no variant '{name}' (VARIANTS of this script)")
        coupled = change.get("algorithm.reflow_pairs") == "coupled"
        coef = change.get("algorithm.reflow_coef")
        if not change:
            roles["base"] = name
        elif change.get("advantages") == "positive":
            roles["positive"] = name
        elif change.get("advantages") == "negative":
            roles["negative"] = name
        elif coef == 0.0 and not coupled:
            roles["no_reflow"] = name
        elif coupled and coef is None:
            roles["coupled"] = name
        elif coupled:
            roles["coupled_high"] = name
        else:
            roles["high"] = name
    return roles


def load_page_data() -> SimpleNamespace:
    """The page's inputs: the thresholds of criteria.yaml, one_step.json's numbers, the runs' rows, the sweep's tasks
    and names, the probed seed, and ``runs(label, task, key[, rows])`` (seed -> value) and ``lam(label[, task])`` (the
    Reflow coefficient at the end of training). The sections add what later sections read (``vars(c).update``)."""
    rules = st.criteria()
    below = rules["collapse_below"]
    settle_window = rules["summaries"]["settle_window"]
    alike_within = rules["summaries"]["alike_within"]
    small_tau_below = rules["summaries"]["small_tau"]
    numbers = json.loads((HERE / "one_step.json").read_text(encoding="utf-8"))
    training, probes, inter = numbers["training"], numbers["probes"], numbers["intervention"]
    rows, dmc = st.read_rows(HERE / "report" / "runs.csv"), st.read_rows(st.CPU_DMC_RUNS)
    spec = st.sweep_spec(st.ROOT / "configs" / "sweep" / "cpu_reflow_pairs.yaml")
    names = st.method_names(spec)
    tasks = list(spec["tasks"])
    pm_task = "dmc_point_mass"

    def runs(label, task, key, source=rows):
        return st.per_seed(source, label, task, key)

    def lam(label, task="dmc_point_mass"):
        return training[task][label]["Flow/reflow_coef"]

    seed = int(next(HERE.glob("dmc_point_mass_probe_seed*.png")).stem.rsplit("seed", 1)[1])

    return SimpleNamespace(
        alike_within=alike_within,
        below=below,
        dmc=dmc,
        inter=inter,
        lam=lam,
        names=names,
        pm_task=pm_task,
        probes=probes,
        rows=rows,
        runs=runs,
        seed=seed,
        settle_window=settle_window,
        small_tau_below=small_tau_below,
        spec=spec,
        tasks=tasks,
        training=training,
    )
