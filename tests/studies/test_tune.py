"""refpo tune: the tuning file's checks before anything starts, the objective by hand, the enqueued own-config values,
and a real tiny study (GridWorld runs as separate processes): records, the intermediate values the pruner reads,
a cut-off trial trained again with its values in its folder, and the fresh-seed sweep written when every method is
done."""

import csv
import json
import sys
from pathlib import Path

import optuna
import pytest
import yaml
from tiny_runs import TINY  # tests/studies/tiny_runs.py

from refpo_warp.studies.grid.spec import load_sweep
from refpo_warp.studies.tuning.records import CHOSEN_FILE, EVALUATION_FILE, TRIALS_FILE, evaluation_sweep
from refpo_warp.studies.tuning.spec import Objective, load_tuning
from refpo_warp.studies.tuning.study import JOURNAL_FILE, Tuner
from refpo_warp.studies.tuning.trial import periodic_returns
from refpo_warp.studies.tuning.values import config_values
from refpo_warp.utils.errors import ConfigError

LR = {"algorithm.learning_rate": {"low": 1.0e-4, "high": 3.0e-3, "log": True}}


def write_tuning(path, **spec):
    base = {
        "device": "cpu",
        "tasks": ["gridworld"],
        "seed": 101,
        "trials": 1,
        "overrides": TINY,
        "objective": {"metric": "return_multi", "reference": {"gridworld": 20.0}},
        "methods": [{"label": "ppo", "algo": "ppo", "space": LR}],
    }
    path.write_text(yaml.safe_dump({**base, **spec}))
    return path


def test_the_objective_is_the_mean_of_the_normalised_returns():
    objective = Objective("return_multi", {"a": 800.0, "b": 400.0})
    assert objective.score({"a": 400.0, "b": 400.0}) == pytest.approx((0.5 + 1.0) / 2)


def test_a_bad_tuning_file_fails_before_anything_starts(tmp_path):
    out = tmp_path / "out"
    cases = {
        "Did you mean 'trials'": {"trails": 3},
        "one positive number for each of": {"objective": {"metric": "return_multi", "reference": {"dmc_x": 1.0}}},
        "set by the tuner": {"methods": [{"algo": "ppo", "space": {"seed": {"choices": [1, 2]}}}]},
        "needs finite low < high": {
            "methods": [{"algo": "ppo", "space": {"algorithm.learning_rate": {"low": 1, "high": 0}}}]
        },
        "both fixes and searches": {
            "methods": [{"algo": "ppo", "overrides": {"algorithm.learning_rate": 1e-3}, "space": LR}]
        },
    }
    for message, spec in cases.items():
        with pytest.raises(ConfigError, match=message):
            load_tuning(str(write_tuning(tmp_path / "t.yaml", **spec)), [f"out={out}"])
    # Resolving every method's runs: a typo in a key, or an enqueued value outside its space.
    typo = write_tuning(
        tmp_path / "typo.yaml",
        methods=[{"algo": "ppo", "space": {"algorithm.learning_rat": LR["algorithm.learning_rate"]}}],
    )
    with pytest.raises(ConfigError, match=r"Did you mean 'algorithm.learning_rate'"):
        Tuner(load_tuning(str(typo), [f"out={out}"])).run()
    outside = write_tuning(
        tmp_path / "outside.yaml",
        methods=[{"algo": "refpo", "space": {"algorithm.num_mc_samples": {"choices": [4, 8]}}}],
    )
    with pytest.raises(ConfigError, match=r"enqueued algorithm.num_mc_samples = 50 lies outside its space \{4, 8\}"):
        Tuner(load_tuning(str(outside), [f"out={out}"])).run()
    assert not out.exists()


def test_the_first_trial_is_the_methods_own_config():
    tuning = load_tuning("cpu_dmc")
    values = {m.label: config_values(tuning, m) for m in tuning.methods}
    # PPO at the paper's values (entropy and the initial std: the classes' defaults); FPO++ at the CPU profile's
    # values, since this study the ones it chose (its authors' values: configs/algo/fpo_pp.yaml, the CUDA profile).
    assert values["ppo"] == {
        "algorithm.learning_rate": 3e-4,
        "algorithm.clip_param": 0.1,
        "algorithm.num_learning_epochs": 8,
        "algorithm.entropy_coef": 0.01,
        "actor.distribution_cfg.init_std": 1.0,
    }
    assert values["refpo"]["algorithm.reflow_coef"] == 0.04 and values["refpo"]["actor.output_scale"] == 0.25
    assert values["fpo_pp"]["algorithm.learning_rate"] == pytest.approx(1.4716e-3, rel=1e-4)
    assert values["fpo_pp"]["algorithm.num_mc_samples"] == 16


def test_periodic_returns_skip_a_line_being_written(tmp_path):
    rows = [
        {"iteration": 0, "eval/return_N10": 3.0, "eval/return_N1": 1.0},
        {"iteration": 1},
        {"iteration": 2, "eval/return": 5.0},
    ]
    (tmp_path / "progress.jsonl").write_text("\n".join(json.dumps(r) for r in rows) + '\n{"iteration": 3, "eval/ret')
    assert periodic_returns(tmp_path) == [3.0, 5.0]
    assert periodic_returns(tmp_path / "none") == []


@pytest.mark.slow(minutes=0.6)
def test_a_tiny_study_resumes_a_cut_off_trial_and_writes_its_records(tmp_path):
    out = tmp_path / "out"
    spec = write_tuning(
        tmp_path / "tiny.yaml",
        pruner=None,
        methods=[
            {"label": "ppo", "algo": "ppo", "space": LR},
            {"label": "refpo", "algo": "refpo", "space": {**LR, "algorithm.num_mc_samples": {"choices": [8, 50]}}},
        ],
        evaluate={
            "tasks": ["gridworld"],
            "seeds": [11],
            "variants": [{"label": "onestep", "of": "refpo", "algo": "refpo_onestep"}],
        },
    )
    lines: list[str] = []
    assert Tuner(load_tuning(str(spec), [f"out={out}"]), echo=lines.append).run()
    assert (out / JOURNAL_FILE).exists() and (out / EVALUATION_FILE).exists()
    # Cut off: a second ppo trial started by a tuner that then died (the trial is left running in the journal).
    storage = optuna.storages.JournalStorage(optuna.storages.journal.JournalFileBackend(str(out / JOURNAL_FILE)))
    study = optuna.load_study(study_name="ppo", storage=storage)
    cut = study.ask()
    cut.suggest_float("algorithm.learning_rate", 1e-4, 3e-3, log=True)
    cut.set_user_attr("slot", 1)
    lr = cut.params["algorithm.learning_rate"]
    more = load_tuning(str(spec), [f"out={out}", "trials=2"])
    studies = {m.label: optuna.load_study(study_name=m.label, storage=storage) for m in more.methods}
    assert evaluation_sweep(more, studies) is None  # not before every method has spent its trials
    lines.clear()
    spec.write_text(
        spec.read_text().replace("\n  num_envs: 4", "\n  num_envs: 6")
    )  # the trials' env count changed since
    assert Tuner(load_tuning(str(spec), [f"out={out}", "trials=2"]), echo=lines.append).run()
    assert sum("[tune] note: " in line and "num_envs: 4 -> 6" in line for line in lines) == 2, lines
    assert any(line.startswith("[tune ppo 2/2] trial 01: learning_rate=" + f"{lr:.3g}") for line in lines), lines
    rows = list(csv.DictReader((out / TRIALS_FILE).open()))
    assert [(r["method"], r["trial"], r["state"], r["enqueued"]) for r in rows] == [
        ("ppo", "0", "complete", "True"),
        ("ppo", "1", "complete", "False"),
        ("refpo", "0", "complete", "True"),
        ("refpo", "1", "complete", "False"),
    ]
    assert float(rows[1]["algorithm.learning_rate"]) == lr and (out / "ppo" / "trial01" / "gridworld").is_dir()
    for row in rows:  # the score: the final N = 10 return (PPO: its mean action) over the reference
        assert float(row["score"]) == pytest.approx(float(row["gridworld/return_multi"]) / 20.0)
    # The pruner's values: each periodic evaluation's return over the reference, in order.
    study = optuna.load_study(study_name="refpo", storage=storage)
    first = next(t for t in study.trials if t.state.name == "COMPLETE")
    curve = periodic_returns(out / "refpo" / f"trial{first.user_attrs['slot']:02d}" / "gridworld")
    assert len(curve) == 2 and first.intermediate_values == {i: v / 20.0 for i, v in enumerate(curve)}
    chosen = yaml.safe_load((out / CHOSEN_FILE).read_text())
    assert set(chosen) == {"ppo", "refpo"} and chosen["ppo"]["trials_spent"] == 2
    # The fresh-seed sweep: each method's chosen values, the variant with ReFPO's; without the trials' overrides.
    sweep = load_sweep(str(out / EVALUATION_FILE))
    assert [m.label for m in sweep.methods] == ["ppo", "refpo", "onestep"] and sweep.seeds == [11]
    assert sweep.methods[2].algo == "refpo_onestep" and sweep.methods[2].overrides == chosen["refpo"]["overrides"]
    assert "max_iterations" not in sweep.methods[0].overrides


@pytest.mark.slow(minutes=0.4)
def test_a_trial_run_that_fails_is_retried_by_the_executor_and_without_retries_fails_the_trial(tmp_path):
    """The trials run through the sweep's executor: a run that exits non-zero (its first start, through the launcher
    prefix fail_once.py) is retried from scratch and the trial completes; with --retries 0 the trial fails, says why
    and counts against the budget."""
    fail_once = f"{sys.executable} {Path(__file__).with_name('fail_once.py')}"
    spec = write_tuning(tmp_path / "tiny.yaml", pruner=None)
    out = tmp_path / "out"
    lines: list[str] = []
    tuner = Tuner(load_tuning(str(spec), [f"out={out}"]), echo=lines.append, launcher=f"{fail_once} {tmp_path / 'a'}")
    assert tuner.run(), "\n".join(lines)
    trial, run_dir = out / "ppo" / "trial00", out / "ppo" / "trial00" / "gridworld"
    status = json.loads((trial / "status.json").read_text())["gridworld/ppo/seed101"]
    assert (status["state"], status["attempts"], status["exit_codes"]) == ("done", 2, [1, 0]), lines
    first = (run_dir / "train.attempt1.log").read_text().splitlines()
    assert first[0].startswith("# tune tiny, ppo trial 00, attempt 1 on ") and "fail_once.py" in first[0]
    assert first[1] == "error: fail_once.py fails the first run it starts"
    assert (run_dir / "train.log").read_text().startswith("# tune tiny, ppo trial 00, attempt 2 on ")
    assert any("FAILED gridworld/ppo/seed101 (attempt 1, exit 1" in line for line in lines), lines
    rows = list(csv.DictReader((out / TRIALS_FILE).open()))
    assert [(r["state"], r["why"]) for r in rows] == [("complete", "")]
    assert float(rows[0]["score"]) == pytest.approx(float(rows[0]["gridworld/return_multi"]) / 20.0)
    report = json.loads((run_dir / "eval.json").read_text())
    assert (
        float(rows[0]["gridworld/return_multi"]) == report["results"]["mean_action"]["return_mean"]
    )  # PPO: its mean action

    # No retries: the first start fails the trial, which is spent (the budget of 1 is used up), with its log named.
    out = tmp_path / "no_retries"
    tuner = Tuner(
        load_tuning(str(spec), [f"out={out}"]), echo=lines.append, retries=0, launcher=f"{fail_once} {tmp_path / 'b'}"
    )
    assert tuner.run()
    rows = list(csv.DictReader((out / TRIALS_FILE).open()))
    log = out / "ppo" / "trial00" / "gridworld" / "train.log"
    assert [(r["state"], r["score"], r["why"]) for r in rows] == [("fail", "", f"gridworld exited 1; log {log}")]
    assert (
        json.loads((out / "ppo" / "trial00" / "status.json").read_text())["gridworld/ppo/seed101"]["state"] == "failed"
    )
