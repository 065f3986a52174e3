"""The bounded learning checks (``tests/learning/checks.py``): each trains seed 1 on one torch thread and asserts its
bound against the policy it started from, measured in the same test. Their runs over seeds and threads, their null
controls and the margins: ``docs/results/learning_checks.md``.

    python -m pytest -m slow tests/learning                                # CI's checks, longest first
    python -m pytest -m slow tests/learning --all-checks                   # and the ones CI leaves (in_ci=False)
    python -m pytest -m slow tests/learning --all-checks --null-control    # each with learning off: must fail
"""

import importlib.util

import pytest
from checks import CHECKS, run_check  # tests/learning/checks.py


def marks(check):
    out = [pytest.mark.slow(minutes=check.minutes), *([] if check.in_ci else [pytest.mark.on_demand])]
    if check.runner == "mjlab" and importlib.util.find_spec("mjlab") is None:
        out.append(pytest.mark.skip(reason="mjlab is not installed: the mjlab job runs it in its venv (.ci/mjlab)"))
    elif check.runner != "mjlab" and importlib.util.find_spec("warp") is None:
        out.append(pytest.mark.skip(reason="needs the sim extra (warp, newton)"))
    elif check.runner in ("finetune", "clones") and importlib.util.find_spec("minari") is None:
        out.append(pytest.mark.skip(reason="needs the data extra (minari) for its demonstrations"))
    return out


@pytest.mark.parametrize("name", [pytest.param(name, marks=marks(check)) for name, check in CHECKS.items()])
def test_learning_check(name, tmp_run_dir, null_control):
    check = CHECKS[name]
    record = run_check(check, seed=1, run_dir=tmp_run_dir, null=null_control)
    passed, stats = check.verdict(record)
    shown = ", ".join(f"{k} {v:.3f}" for k, v in stats.items())
    print(
        f"[learning check] {name}{' (null control)' if null_control else ''}: {shown}; bounds "
        f"{', '.join(map(str, check.bounds))}",
        flush=True,
    )
    if null_control:
        assert not passed, f"{name} passes with learning switched off: {shown}"
        return
    assert passed, f"{name}: {shown} against {', '.join(map(str, check.bounds))}"
    assert not check.properties(record), check.properties(record)
    if check.runner != "mjlab":  # mjlab's evaluation reports one return rate, not per-setting summaries
        nonfinite = [s for s, summary in record["final"].items() if summary.get("nonfinite_resets_mean", 0) > 0]
        assert not nonfinite, f"non-finite env states reset during evaluation: {nonfinite}"
