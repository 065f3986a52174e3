"""An equal tuning budget for every method (``refpo tune``): one Optuna study per method, each trial a training run
per task on the tuning seed, scored by the objective the tuning file states before the search.

- **Equal budget.** Methods take turns, one trial each per round, until each has spent ``trials``; a pruned or failed
  trial is spent too. The first trials of a method are its enqueued values (its own config's, e.g. the paper's), then
  TPE samples the declared space; the sampler is seeded from (tuning seed, method, trial), so a resumed search draws
  what an uninterrupted one would.
- **Pruning.** After each periodic evaluation that every task's run has reached, the trial reports the objective on
  those evaluations (its intermediate values, also without a pruner); a trial in the lowest ``percentile`` of
  earlier trials at that evaluation (after
  ``warmup_evaluations``) is stopped.
- **Resumable.** The studies live in ``<out>/journal.log`` (Optuna's journal storage: one JSON line per event). A
  trial cut off (Ctrl-C, a killed session) is trained again with the same values in the same folder, where a run that
  had finished (its ``eval.json`` of the same config) is kept.
- **Records.** ``<out>/trials.csv`` lists every trial with its values, state, score and per-task returns;
  ``<out>/chosen.yaml`` each method's best completed trial. Both are rewritten after every trial.
"""

from __future__ import annotations

import csv
import io
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from refpo_warp.studies.grid.launch import hostname, start_training, stop_training, train_command, train_env
from refpo_warp.studies.grid.run_metrics import run_metrics
from refpo_warp.studies.grid.spec import Run, fingerprint
from refpo_warp.studies.grid.state import LOG_FILE, run_state
from refpo_warp.studies.tuning.spec import CONFIG_VALUES, Dimension, TunedMethod, Tuning
from refpo_warp.utils.atomic_files import write_text
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.rng import stream_seed

JOURNAL_FILE = "journal.log"
TRIALS_FILE = "trials.csv"
CHOSEN_FILE = "chosen.yaml"
EVALUATION_FILE = "evaluate.yaml"  # the sweep of the chosen values on fresh seeds (tuning files with `evaluate`)
POLL_S = 2.0
# The periodic return the pruner reads: a flow's N = 10 (as the objective's 10-step column), else a Gaussian's mean.
CURVE_KEYS = ("eval/return_N10", "eval/return")


def _optuna():
    try:
        import optuna
    except ImportError as err:
        raise ConfigError('refpo tune needs Optuna: pip install "refpo-warp[tune]"') from err
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    return optuna


def _duration(seconds: float) -> str:
    seconds = round(seconds)
    h, rest = divmod(seconds, 3600)
    return f"{h}h{rest // 60:02d}m" if h else f"{rest // 60}m{rest % 60:02d}s"


# ------------------------------------------------------------------------------------------------ config values
def run_config(tuning: Tuning, run: Run) -> dict:
    """A trial run's config, resolved as its ``refpo train`` process will."""
    from refpo_warp.config.dotted import parse_overrides
    from refpo_warp.config.resolve import resolve_config
    from refpo_warp.studies.grid.spec import device_type

    return resolve_config(
        parse_overrides([*run.args, f"device={tuning.device}"]), device_type=device_type(tuning.device)
    )


def _resolve(tuning: Tuning, method: TunedMethod, task: str, values: dict[str, Any]) -> dict:
    return run_config(tuning, tuning.trial_runs(method, 0, values)[tuning.tasks.index(task)])


def option_value(cfg: dict, key: str) -> Any:
    """A dotted option of a resolved config; an unset constructor argument reads its class's default."""
    from refpo_warp.config.classes import class_parameters

    node: Any = cfg
    parts = key.split(".")
    for i, part in enumerate(parts[:-1]):
        if not isinstance(node, dict) or not isinstance(node.get(part), dict):
            choices = [".".join([*parts[:i], k]) for k, v in node.items() if isinstance(v, dict)]
            raise unknown("config section", ".".join(parts[: i + 1]), choices)
        node = node[part]
    params = class_parameters(node["class_name"]) if "class_name" in node else {}
    if parts[-1] in node:
        return node[parts[-1]]
    if parts[-1] in params:
        return params[parts[-1]]
    section = ".".join(parts[:-1])
    raise unknown(f"option of {section}", key, [f"{section}.{k}" for k in sorted({*node, *params})])


def config_values(tuning: Tuning, method: TunedMethod) -> dict[str, Any]:
    """The searched options' values in the method's own config (the first task's profile)."""
    cfg = _resolve(tuning, method, tuning.tasks[0], {})
    return {d.key: option_value(cfg, d.key) for d in method.space}


def enqueued_values(tuning: Tuning, method: TunedMethod) -> list[dict[str, Any]]:
    out = []
    for item in method.enqueue:
        values = config_values(tuning, method) if item == CONFIG_VALUES else dict(item)
        for dim in method.space:
            if dim.key not in values:
                raise ConfigError(f"Method '{method.label}': an enqueued trial lacks '{dim.key}'")
            if not dim.contains(values[dim.key]):
                raise ConfigError(
                    f"Method '{method.label}': enqueued {dim.key} = {values[dim.key]!r} lies outside "
                    f"its space {dim.describe()}"
                )
        extra = sorted(set(values) - {d.key for d in method.space})
        if extra:
            raise ConfigError(f"Method '{method.label}': enqueued values of options not searched: {extra}")
        out.append({d.key: values[d.key] for d in method.space})
    return out


def validate(tuning: Tuning) -> dict[str, list[dict[str, Any]]]:
    """Resolve every method's runs at its enqueued values and at each dimension's extremes, on every task, as
    ``refpo train`` will; returns the enqueued values per method. Every failure is collected and raised together."""
    errors: list[str] = []
    enqueued: dict[str, list[dict[str, Any]]] = {}
    for method in tuning.methods:
        try:
            enqueued[method.label] = enqueued_values(tuning, method)
        except ConfigError as err:
            errors.append(f"- {method.label}: {err}")
            continue
        base = enqueued[method.label][0] if enqueued[method.label] else {}
        probes = [base] + [{**base, d.key: v} for d in method.space for v in (d.choices or (d.low, d.high))]
        for task in tuning.tasks:
            for values in probes:
                try:
                    cfg = _resolve(tuning, method, task, values)
                    if not cfg["eval"]["at_end"]:
                        raise ConfigError("eval.at_end is false: a trial run must write eval.json")
                except ConfigError as err:
                    errors.append(f"- {method.label} on {task} at {values}: {err}")
                    break
    if errors:
        raise ConfigError(
            f"Tuning '{tuning.name}': {len(errors)} method config(s) do not resolve:\n" + "\n".join(errors)
        )
    return enqueued


# ------------------------------------------------------------------------------------------------ one trial
def periodic_returns(run_dir: Path) -> list[float]:
    """The periodic evaluation returns logged so far (``progress.jsonl``; a line being written is skipped)."""
    path = run_dir / "progress.jsonl"
    if not path.exists():
        return []
    out = []
    for line in path.read_text().splitlines():
        try:
            row = json.loads(line)
        except ValueError:
            continue
        for key in CURVE_KEYS:
            if key in row:
                out.append(float(row[key]))
                break
    return out


@dataclass
class TrialResult:
    state: str  # complete | pruned | failed | interrupted
    score: float | None
    values: dict[str, dict[str, float]]  # task -> run metrics (final evaluation)
    seconds: float
    why: str = ""


class TrialRunner:
    """Trains one trial's runs (``jobs`` at a time), reports the objective at every periodic evaluation that all
    runs have reached and stops them when the trial is pruned."""

    def __init__(self, tuning: Tuning, jobs: int, echo=print) -> None:
        self.tuning, self.jobs, self.echo = tuning, max(1, jobs), echo
        self.host = hostname()

    def run(self, runs: list[Run], trial, header: str) -> TrialResult:
        started = time.monotonic()
        prints = {run.task: fingerprint(run_config(self.tuning, run)) for run in runs}
        todo = [run for run in runs if run_state(run, prints[run.task]) != "done"]
        kept = [run.task for run in runs if run not in todo]
        if kept:
            self.echo(f"        kept finished run(s) of an earlier attempt: {', '.join(kept)}")
        running: dict[str, Any] = {}
        reported = 0
        reference = self.tuning.objective.reference
        device = self.tuning.device if self.tuning.device != "auto" else "cpu"
        env = train_env(os.environ, 1 if device == "cpu" else None)
        try:
            while todo or running:
                while todo and len(running) < self.jobs:
                    run = todo.pop(0)
                    cmd = train_command(run.args, device)
                    # detached: a run dies with the tuner however it dies (a restart would clear its folder)
                    running[run.task] = (run, start_training(run.run_dir, header, cmd, env, os.getcwd(), detach=True))
                time.sleep(POLL_S)
                for task, (run, proc) in list(running.items()):
                    if proc.poll() is None:
                        continue
                    del running[task]
                    if proc.returncode != 0 or run_state(run, prints[task]) != "done":
                        stop_training([p for _, p in running.values()])
                        why = f"{task} exited {proc.returncode}; log {run.run_dir / LOG_FILE}"
                        return TrialResult("failed", None, {}, time.monotonic() - started, why)
                curves = {run.task: periodic_returns(run.run_dir) for run in runs}
                common = min(len(c) for c in curves.values())
                while reported < common:
                    trial.report(sum(curves[t][reported] / reference[t] for t in reference) / len(reference), reported)
                    reported += 1
                    if trial.should_prune():
                        stop_training([p for _, p in running.values()])
                        return TrialResult(
                            "pruned", None, {}, time.monotonic() - started, f"at periodic evaluation {reported}"
                        )
        except KeyboardInterrupt:
            stop_training([p for _, p in running.values()])
            return TrialResult("interrupted", None, {}, time.monotonic() - started)
        values = {}
        for run in runs:
            report = json.loads((run.run_dir / "eval.json").read_text())
            values[run.task] = run_metrics(report)[0]
        metric = self.tuning.objective.metric
        missing = [t for t, v in values.items() if metric not in v]
        if missing:
            return TrialResult(
                "failed", None, values, time.monotonic() - started, f"eval.json of {missing} has no '{metric}'"
            )
        score = self.tuning.objective.score({t: v[metric] for t, v in values.items()})
        return TrialResult("complete", score, values, time.monotonic() - started)


# ------------------------------------------------------------------------------------------------ the studies
def _suggest(trial, dim: Dimension) -> Any:
    if dim.choices:
        return trial.suggest_categorical(dim.key, list(dim.choices))
    return trial.suggest_float(dim.key, dim.low, dim.high, log=dim.log)


def _spent(study) -> list:
    """The trials that count against the budget: completed, pruned and failed ones (a failure says why); not those
    cut off by an interruption (failed without a reason, and enqueued again)."""
    from optuna.trial import TrialState

    return [
        t
        for t in study.trials
        if t.state in (TrialState.COMPLETE, TrialState.PRUNED) or (t.state == TrialState.FAIL and "why" in t.user_attrs)
    ]


class Tuner:
    def __init__(self, tuning: Tuning, jobs: int | None = None, echo=print) -> None:
        self.tuning, self.echo = tuning, echo
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        self.jobs = jobs or min(len(tuning.tasks), cores)
        self.optuna = _optuna()

    def _storage(self):
        from optuna.storages.journal import JournalFileBackend, JournalStorage

        self.tuning.out_dir.mkdir(parents=True, exist_ok=True)
        return JournalStorage(JournalFileBackend(str(self.tuning.out_dir / JOURNAL_FILE)))

    def _pruner(self):
        p = self.tuning.pruner
        if p is None:
            return self.optuna.pruners.NopPruner()
        return self.optuna.pruners.PercentilePruner(
            p["percentile"], n_startup_trials=p["startup_trials"], n_warmup_steps=p["warmup_evaluations"]
        )

    def studies(self, storage, enqueued: dict[str, list[dict]]) -> dict[str, Any]:
        """One study per method (created with its enqueued trials first); trials left running by a process that
        died are marked failed-by-interruption and enqueued again with their values and folder."""
        from optuna.trial import TrialState

        out = {}
        for method in self.tuning.methods:
            study = self.optuna.create_study(
                study_name=method.label,
                storage=storage,
                direction="maximize",
                load_if_exists=True,
                pruner=self._pruner(),
            )
            if not study.trials:
                for i, values in enumerate(enqueued[method.label]):
                    study.enqueue_trial(values, user_attrs={"slot": i, "enqueued": True})
            self._check_configs(study, method, enqueued[method.label][0] if enqueued[method.label] else {})
            for t in study.trials:
                if t.state == TrialState.RUNNING:
                    self._requeue(study, t)
            out[method.label] = study
        return out

    def _check_configs(self, study, method: TunedMethod, values: dict[str, Any]) -> None:
        """A search spans sessions, and its trials compare only if the code resolves a method's runs as it did when
        the search began: the first start records the configs at the first trial's values, a later start names every
        option that now resolves differently."""
        from refpo_warp.config.dotted import flatten

        now = {task: json.loads(json.dumps(_resolve(self.tuning, method, task, values))) for task in self.tuning.tasks}
        for cfg in now.values():
            for key in ("run_dir", "device", "config_dir"):
                cfg.pop(key, None)
        then = study.user_attrs.get("configs")
        if then is None:
            study.set_user_attr("configs", now)
            return
        for task in self.tuning.tasks:
            old, new = flatten(then.get(task, {})), flatten(now[task])
            changed = [
                f"{k}: {old.get(k, '(absent)')} -> {new.get(k, '(absent)')}"
                for k in sorted({*old, *new})
                if old.get(k, "(absent)") != new.get(k, "(absent)")
            ]
            if changed:
                self.echo(
                    f"[tune] note: {method.label} on {task} resolves differently from when its search began "
                    f"(its trials compare across both): " + "; ".join(changed)
                )

    @staticmethod
    def _requeue(study, trial) -> None:
        """A trial cut off: failed without a reason (not spent), and its values enqueued again for its folder."""
        from optuna.trial import TrialState

        study.tell(trial.number, state=TrialState.FAIL, skip_if_finished=True)
        study.enqueue_trial(trial.params, user_attrs={k: v for k, v in trial.user_attrs.items() if k != "seconds"})

    def run(self, dry_run: bool = False) -> bool:
        """Run the rounds until every method has spent its trials; returns False when interrupted."""
        t = self.tuning
        enqueued = validate(t)
        self.echo(
            f"[tune] {t.name}: {len(t.methods)} method(s) x {t.trials} trials, each trial {len(t.tasks)} run(s) "
            f"({', '.join(t.tasks)}) on seed {t.seed}, {self.jobs} at a time; every config resolves"
        )
        self.echo(
            f"[tune] objective: mean over tasks of {t.objective.metric} / "
            + ", ".join(f"{k} {v:g}" for k, v in t.objective.reference.items())
        )
        if dry_run:
            for method in t.methods:
                self.echo(
                    f"  {method.label}: enqueued {enqueued[method.label]}; space "
                    + ", ".join(f"{d.key} {d.describe()}" for d in method.space)
                )
            return True
        from refpo_warp.studies.grid.lock import SweepLock

        lock = SweepLock(t.out_dir)  # one tuner per folder: another one's running trials are not cut off
        try:
            studies = self.studies(self._storage(), enqueued)
            runner = TrialRunner(t, self.jobs, self.echo)
            start = time.monotonic()
            try:
                for round_ in range(t.trials):
                    for index, method in enumerate(t.methods):
                        if len(_spent(studies[method.label])) > round_:
                            continue
                        if not self._trial(studies, index, method, runner, start):
                            return False
            finally:
                self.write_records(studies)
        finally:
            lock.release()
        self.echo(
            f"[tune] done: {t.trials} trials per method; records: {t.out_dir / TRIALS_FILE}, {t.out_dir / CHOSEN_FILE}"
        )
        if t.evaluation is not None:
            self.echo(f"[tune] the chosen values on fresh seeds: refpo sweep {t.out_dir / EVALUATION_FILE}")
        return True

    def _trial(self, studies: dict, index: int, method: TunedMethod, runner: TrialRunner, start: float) -> bool:
        from optuna.trial import TrialState

        t = self.tuning
        study = studies[method.label]
        spent = len(_spent(study))
        study.sampler = self.optuna.samplers.TPESampler(
            seed=stream_seed(t.seed, index, spent) % 2**32, n_startup_trials=t.startup_trials
        )
        trial = study.ask()
        values = {d.key: _suggest(trial, d) for d in method.space}
        slot = int(trial.user_attrs.get("slot", spent))
        trial.set_user_attr("slot", slot)
        shown = ", ".join(
            f"{k.rsplit('.', 1)[-1]}={v:.3g}" if isinstance(v, float) else f"{k.rsplit('.', 1)[-1]}={v}"
            for k, v in values.items()
        )
        self.echo(f"[tune {method.label} {spent + 1}/{t.trials}] trial {slot:02d}: {shown}")
        header = f"tune {t.name}, {method.label} trial {slot:02d} on {runner.host}"
        result = runner.run(t.trial_runs(method, slot, values), trial, header)
        trial.set_user_attr("seconds", round(result.seconds, 1))
        for task, metrics in result.values.items():
            for metric in ("return_multi", "return_1"):
                if metric in metrics:
                    trial.set_user_attr(f"{task}/{metric}", metrics[metric])
        if result.why:  # a spent trial that did not complete says why
            trial.set_user_attr("why", result.why)
        elapsed = _duration(time.monotonic() - start)
        if result.state == "interrupted":
            self._requeue(study, study.trials[trial.number])
            self.echo(f"[tune] interrupted: {method.label} trial {slot:02d} is trained again on the next start")
            return False
        if result.state == "complete":
            study.tell(trial, result.score)
            returns = "  ".join(
                f"{task} {v.get('return_multi', float('nan')):.1f}" for task, v in result.values.items()
            )
            best = study.best_trial
            self.echo(
                f"        score {result.score:.3f} ({returns}) in {_duration(result.seconds)}; best so far "
                f"trial {best.user_attrs['slot']:02d} {best.value:.3f} | elapsed {elapsed}"
            )
        else:
            study.tell(trial, state=TrialState.PRUNED if result.state == "pruned" else TrialState.FAIL)
            self.echo(f"        {result.state} {result.why} in {_duration(result.seconds)} | elapsed {elapsed}")
        self.write_records(studies)
        return True

    # ------------------------------------------------------------------------------------------------ records
    def write_records(self, studies: dict[str, Any]) -> None:
        write_text(self.tuning.out_dir / TRIALS_FILE, trials_csv(self.tuning, studies))
        write_text(self.tuning.out_dir / CHOSEN_FILE, chosen_yaml(self.tuning, studies))
        sweep = evaluation_sweep(self.tuning, studies)
        if sweep is not None:
            write_text(self.tuning.out_dir / EVALUATION_FILE, sweep)


def trial_rows(tuning: Tuning, studies: dict[str, Any]) -> list[dict[str, Any]]:
    rows = []
    for method in tuning.methods:
        study = studies.get(method.label)
        for t in _spent(study) if study is not None else []:
            row = {
                "method": method.label,
                "trial": t.user_attrs.get("slot", t.number),
                "state": t.state.name.lower(),
                "enqueued": bool(t.user_attrs.get("enqueued")),
                "score": t.value if t.state.name == "COMPLETE" else None,
                "seconds": t.user_attrs.get("seconds"),
            }
            for task in tuning.tasks:
                for metric in ("return_multi", "return_1"):
                    row[f"{task}/{metric}"] = t.user_attrs.get(f"{task}/{metric}")
            row.update({d.key: t.params.get(d.key) for d in method.space})
            row["why"] = t.user_attrs.get("why", "")
            rows.append(row)
    return rows


def trials_csv(tuning: Tuning, studies: dict[str, Any]) -> str:
    rows = trial_rows(tuning, studies)
    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buf.getvalue()


def chosen_values(tuning: Tuning, studies: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Each method's best completed trial: its values, score and trial number (methods without one are left out)."""
    from optuna.trial import TrialState

    out = {}
    for method in tuning.methods:
        study = studies.get(method.label)
        complete = [t for t in (study.trials if study else []) if t.state == TrialState.COMPLETE]
        if not complete:
            continue
        best = max(complete, key=lambda t: t.value)
        out[method.label] = {
            "algo": method.algo,
            "trial": best.user_attrs.get("slot"),
            "score": best.value,
            "trials_spent": len(_spent(study)),
            "overrides": {**method.overrides, **best.params},
        }
    return out


def chosen_yaml(tuning: Tuning, studies: dict[str, Any]) -> str:
    import yaml

    head = (
        f"# refpo tune {tuning.name}: each method's best completed trial (objective: mean over "
        f"{', '.join(tuning.tasks)} of {tuning.objective.metric} / its reference, seed {tuning.seed}).\n"
    )
    return head + yaml.safe_dump(chosen_values(tuning, studies), sort_keys=False)


def evaluation_sweep(tuning: Tuning, studies: dict[str, Any]) -> str | None:
    """The sweep file of the chosen values on fresh seeds (``refpo sweep <out>/evaluate.yaml``), once every method has
    spent its trials and has a completed one; None before. A run keeps its method's own evaluation protocol (the
    tuning's ``overrides`` are for the trials only)."""
    import yaml

    ev = tuning.evaluation
    chosen = chosen_values(tuning, studies)
    done = all(len(_spent(studies[m.label])) >= tuning.trials and m.label in chosen for m in tuning.methods)
    if ev is None or not done:
        return None
    methods = [
        {"label": m.label, "algo": m.algo, "name": f"{m.name} (tuned)", "overrides": chosen[m.label]["overrides"]}
        for m in tuning.methods
    ]
    for v in ev.variants:
        methods.append(
            {
                "label": v["label"],
                "algo": v["algo"],
                "name": f"{v['name']} (tuned {v['of']})",
                "overrides": chosen[v["of"]]["overrides"],
            }
        )
    spec = {
        "description": f"the chosen values of refpo tune {tuning.name} on fresh seeds {ev.seeds}",
        "device": tuning.device,
        "tasks": ev.tasks,
        "seeds": ev.seeds,
        "methods": methods,
        "out": str(tuning.out_dir / "evaluate"),
    }
    head = (
        f"# Written by refpo tune {tuning.name} when every method had spent its {tuning.trials} trials: each "
        f"method's best trial (chosen.yaml). Run: refpo sweep <this file>\n"
    )
    return head + yaml.safe_dump(json.loads(json.dumps(spec)), sort_keys=False)  # a plain copy: no YAML anchors
