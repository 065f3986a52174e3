"""``refpo bench train``: its parts add up to the iteration it times, and it counts the env steps the run takes."""

import itertools
import json

import pytest

from refpo_warp.cli.main import main

ENVS, STEPS, ITERATIONS = 8, 6, 2
MINIBATCHES, EPOCHS = 2, 2


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench") / "train.json"
    argv = [
        "bench",
        "train",
        "task=gridworld",
        "algo=[ppo,refpo]",
        "device=cpu",
        f"num_envs={ENVS}",
        f"runner.num_steps_per_env={STEPS}",
        f"algorithm.num_mini_batches={MINIBATCHES}",
        f"algorithm.num_learning_epochs={EPOCHS}",
        f"iterations={ITERATIONS}",
        "warmup=1",
        f"out={out}",
    ]
    assert main(argv) == 0
    return json.loads(out.read_text())


def test_env_steps_are_iterations_x_envs_x_steps_and_every_part_is_timed_once_per_call(results):
    assert [r["algo"] for r in results["results"]] == ["ppo", "refpo"]
    for row in results["results"]:
        assert (
            row["env_steps_counted"] == ITERATIONS * ENVS * STEPS == row["iterations"] * row["env_steps_per_iteration"]
        )
        calls = row["calls"]
        assert calls["collection/env"] == calls["collection/policy"] == ITERATIONS * STEPS
        assert calls["collection"] == calls["returns"] == calls["update"] == calls["logging"] == ITERATIONS
        # one actor loss, critic loss, backward and optimizer step per minibatch of every pass
        assert calls["update/policy_loss"] == calls["update/optimizer"] == ITERATIONS * MINIBATCHES * EPOCHS
        assert calls["update/backward"] == calls["update/value_loss"] == ITERATIONS * MINIBATCHES * EPOCHS
        assert row["env_steps_per_s"] == pytest.approx(row["env_steps_counted"] / row["seconds"])


def test_the_parts_add_up_to_the_whole(results):
    for row in results["results"]:
        whole, parts = row["seconds_per_iteration"], row["iteration"]
        assert sum(parts.values()) == pytest.approx(whole)
        timed = {k: v for k, v in parts.items() if k != "other"}
        assert all(v >= 0 for v in timed.values())
        # the timed phases hold the iteration: what none holds (the loop, learn's set-up) is a small rest
        assert -1e-3 <= parts["other"] <= 0.1 * whole + 0.02
        for split, total in (("update", parts["update"]), ("collection", parts["collection"])):
            inner = row[split]
            assert all(v >= 0 for k, v in inner.items() if k != "other")
            assert sum(inner.values()) == pytest.approx(total)
            assert -1e-3 <= inner["other"] <= total
    ppo, refpo = results["results"]
    assert refpo["ratio_to_ppo"] == pytest.approx(refpo["env_steps_per_s"] / ppo["env_steps_per_s"])
    # the command recorded repeats the measurement: read back, it gives the same options and run options
    from refpo_warp.benchmarks import train_throughput
    from refpo_warp.cli.bench import parse_bench

    command = results["command"].split()
    assert command[:4] == ["refpo", "bench", "train", "task=gridworld"]
    options, run_options = parse_bench("train", train_throughput, command[3:])
    assert options == train_throughput.Options(algo=["ppo", "refpo"], iterations=ITERATIONS, warmup=1, out=options.out)
    assert run_options == {
        "task": "gridworld",
        "device": "cpu",
        "num_envs": ENVS,
        "runner.num_steps_per_env": STEPS,
        "algorithm.num_mini_batches": MINIBATCHES,
        "algorithm.num_learning_epochs": EPOCHS,
    }
    assert results["machine"]["cpu_count"] >= 1


def test_a_bad_option_names_the_key_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "x.json"
    # the benchmark's own options and the run options it passes on, through the one parser: an unknown key is refused
    # naming the valid ones; the run option the benchmark sets itself (its temporary run dir) is refused naming out=
    for key in ("iteration=3", "train.iterations=3"):
        assert main(["bench", "train", "task=gridworld", key, f"out={out}"]) == 2
        err = capsys.readouterr().err
        assert "Unknown option of refpo bench train" in err and "iterations, max_iterations" in err, err
        assert "algorithm.<option>" in err and "Traceback" not in err and not out.exists()
    assert main(["bench", "train", "task=gridworld", "run_dir=x", f"out={out}"]) == 2
    err = capsys.readouterr().err
    assert "'run_dir=' is spelled 'out=" in err and "Traceback" not in err and not out.exists()
    assert main(["bench", "train", "task=gridworld", "iterations=0", f"out={out}"]) == 2
    assert "iterations" in capsys.readouterr().err and not out.exists()
    assert main(["bench", "train", "task=gridworld", "algo=[ppo,refpoo]", f"out={out}"]) == 2
    assert "refpoo" in capsys.readouterr().err and not out.exists()


def test_the_update_flops_are_the_hand_count_of_ppos_matrix_products(results):
    # PPO on gridworld: observations (x, y) and a 2-D action; actor obs -> 64 -> 64 -> 2, critic obs -> 64 -> 64 -> 1.
    # A layer d_in -> d_out over r rows: 2 r d_in d_out forward, as much for its weight's gradient, and as much for its
    # input's gradient except at the first layer (the observations need none). One update: every transition, every pass.
    def mlp(dims):
        layers = list(itertools.pairwise(dims))
        return sum(4 * i * o for i, o in layers) + sum(2 * i * o for i, o in layers[1:])

    rows = ENVS * STEPS * EPOCHS
    ppo = results["results"][0]["arithmetic"]
    assert ppo["update_matmul_flops"] == rows * (mlp([2, 64, 64, 2]) + mlp([2, 64, 64, 1]))
    for row in results["results"]:
        found = row["arithmetic"]
        assert found["matmul_shape"] == [ENVS * STEPS // MINIBATCHES, 64, 64]
        assert found["update_gflops_per_s"] * 1e9 == pytest.approx(
            found["update_matmul_flops"] / row["iteration"]["update"]
        )
        assert found["share_of_matmul_rate"] == pytest.approx(
            found["update_gflops_per_s"] / found["matmul_gflops_per_s"]
        )
