"""An equal tuning budget for every method (``refpo tune``): one Optuna study per method, each trial a training run
per task on the tuning seed, scored by the objective the tuning file states before the search.

- **Equal budget.** Methods take turns, one trial each per round, until each has spent ``trials``; a pruned or failed
  trial is spent too. The first trials of a method are its enqueued values (its own config's, e.g. the paper's), then
  TPE samples the declared space; the sampler is seeded from (tuning seed, method, trial), so a resumed search draws
  what an uninterrupted one would.
- **Runs.** A trial's runs are trained by the grid's executor (``trial.py``), on the backend a sweep uses (local
  processes or Ray tasks, ``backends.py``), a failed run retried from scratch (``retries``) before the trial fails.
- **Pruning.** After each periodic evaluation that every task's run has reached, the trial reports the objective on
  those evaluations (its intermediate values, also without a pruner); a trial in the lowest ``percentile`` of
  earlier trials at that evaluation (after ``warmup_evaluations``) is stopped.
- **Resumable.** The studies live in ``<out>/journal.log`` (Optuna's journal storage: one JSON line per event). A
  trial cut off (Ctrl-C, a killed session) is trained again with the same values in the same folder, where a run that
  had finished (its ``eval.json`` of the same config) is kept.
- **Records** (``records.py``): ``<out>/trials.csv`` lists every trial with its values, state, score and per-task
  returns; ``<out>/chosen.yaml`` each method's best completed trial. Both are rewritten after every trial.
"""

from __future__ import annotations

import json
import os
import time
from typing import Any

from refpo_warp.studies.backends import check_backend, make_launcher
from refpo_warp.studies.grid.executor import Launcher, duration
from refpo_warp.studies.grid.lock import SweepLock
from refpo_warp.studies.ray.backend import RayOptions
from refpo_warp.studies.tuning.records import CHOSEN_FILE, EVALUATION_FILE, TRIALS_FILE, spent_trials, write_records
from refpo_warp.studies.tuning.spec import Dimension, TunedMethod, Tuning
from refpo_warp.studies.tuning.trial import TrialRunner, study_sweep
from refpo_warp.studies.tuning.values import method_config, validate
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.rng import stream_seed

JOURNAL_FILE = "journal.log"


def _optuna():
    try:
        import optuna
    except ImportError as err:
        raise ConfigError('refpo tune needs Optuna: pip install "refpo-warp[tune]"') from err
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    return optuna


def _suggest(trial, dim: Dimension) -> Any:
    if dim.choices:
        return trial.suggest_categorical(dim.key, list(dim.choices))
    return trial.suggest_float(dim.key, dim.low, dim.high, log=dim.log)


class Tuner:
    """The studies of a tuning, their trials trained by ``backend`` (``refpo sweep``'s: ``local`` or ``ray`` with its
    ``RayOptions``), ``jobs`` runs of a trial at a time, ``retries`` of a failed run, ``launcher`` prefixing each
    training command."""

    def __init__(
        self,
        tuning: Tuning,
        jobs: int | None = None,
        echo=print,
        retries: int = 1,
        launcher: str = "",
        backend: str = "local",
        ray: RayOptions | None = None,
    ) -> None:
        self.tuning, self.echo, self.retries, self.prefix = tuning, echo, retries, launcher
        self.backend, self.ray, self.jobs = backend, ray, jobs
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        self.local_jobs = jobs or min(len(tuning.tasks), cores)  # on Ray: what the cluster fits, unless given
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

        now = {
            task: json.loads(json.dumps(method_config(self.tuning, method, task, values))) for task in self.tuning.tasks
        }
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
        grid = study_sweep(t, t.out_dir)
        check_backend(self.backend, grid, self.ray)  # the options' own checks first
        enqueued = validate(t)
        launcher = None
        if not dry_run:  # detached: a run dies with the tuner however it dies (a restart clears its folder)
            jobs = self.local_jobs if self.backend == "local" else self.jobs
            launcher = make_launcher(self.backend, grid, jobs, self.prefix, self.ray, self.echo, detach=True)
        try:
            self._plan(enqueued, launcher)
            return launcher is None or self._rounds(enqueued, launcher)
        finally:
            if launcher is not None:
                launcher.close()

    def _plan(self, enqueued: dict[str, list[dict]], launcher: Launcher | None) -> None:
        t = self.tuning
        jobs = min(launcher.jobs, len(t.tasks)) if launcher else self.local_jobs
        where = f" {launcher.where}" if launcher and self.backend != "local" else ""
        self.echo(
            f"[tune] {t.name}: {len(t.methods)} method(s) x {t.trials} trials, each trial {len(t.tasks)} run(s) "
            f"({', '.join(t.tasks)}) on seed {t.seed}, {jobs} at a time{where}; every config resolves"
        )
        self.echo(
            f"[tune] objective: mean over tasks of {t.objective.metric} / "
            + ", ".join(f"{k} {v:g}" for k, v in t.objective.reference.items())
        )
        if launcher is None:
            for method in t.methods:
                self.echo(
                    f"  {method.label}: enqueued {enqueued[method.label]}; space "
                    + ", ".join(f"{d.key} {d.describe()}" for d in method.space)
                )

    def _rounds(self, enqueued: dict[str, list[dict]], launcher: Launcher) -> bool:
        t = self.tuning
        lock = SweepLock(t.out_dir)  # one tuner per folder: another one's running trials are not cut off
        try:
            launcher.prepare(study_sweep(t, t.out_dir))
            studies = self.studies(self._storage(), enqueued)
            runner = TrialRunner(t, launcher, self.retries, self.echo)
            start = time.monotonic()
            try:
                for round_ in range(t.trials):
                    for index, method in enumerate(t.methods):
                        if len(spent_trials(studies[method.label])) > round_:
                            continue
                        if not self._trial(studies, index, method, runner, start):
                            return False
            finally:
                write_records(t, studies)
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
        spent = len(spent_trials(study))
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
        origin = f"tune {t.name}, {method.label} trial {slot:02d}"
        result = runner.run(t.trial_runs(method, slot, values), trial, origin)
        trial.set_user_attr("seconds", round(result.seconds, 1))
        for task, metrics in result.values.items():
            for metric in ("return_multi", "return_1"):
                if metric in metrics:
                    trial.set_user_attr(f"{task}/{metric}", metrics[metric])
        if result.why:  # a spent trial that did not complete says why
            trial.set_user_attr("why", result.why)
        elapsed = duration(time.monotonic() - start)
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
                f"        score {result.score:.3f} ({returns}) in {duration(result.seconds)}; best so far "
                f"trial {best.user_attrs['slot']:02d} {best.value:.3f} | elapsed {elapsed}"
            )
        else:
            study.tell(trial, state=TrialState.PRUNED if result.state == "pruned" else TrialState.FAIL)
            self.echo(f"        {result.state} {result.why} in {duration(result.seconds)} | elapsed {elapsed}")
        write_records(t, studies)
        return True
