"""The learning checks' documented table matches their committed records, every check has the runs its rule asks for
(seeds 1-5 on one torch thread, 1-3 on two, the null control on 1-3), and every bound obeys the rule: strictly beyond
the null control's best run and at most halfway from it to the learning runs' worst, or, for a claim bound, met by every
learning run beside a bound of the first kind (tests/learning/table.py)."""

import sys

import pytest

from refpo_warp.utils.paths import REPO_ROOT

sys.path.insert(0, str(REPO_ROOT / "tests" / "learning"))
from checks import CHECKS  # (tests/learning/checks.py)
from measure import RESULTS, read_records
from table import BEGIN, END, standings, table_markdown

RECORDS = read_records()


@pytest.mark.parametrize("name", list(CHECKS))
def test_bounds_sit_between_the_null_control_and_the_learning_runs(name):
    bounds, missing = standings(CHECKS[name], RECORDS)
    assert not missing, f"runs missing from docs/results/learning_checks/records: {missing}"
    problems = [p for standing in bounds for p in standing.problems()]
    assert not problems, problems
    assert any(not b.claim for b in CHECKS[name].bounds), f"{name}: only claim bounds, none the null control must fail"


def test_the_documented_table_is_the_records_table():
    text = (RESULTS.parent / "learning_checks.md").read_text(encoding="utf-8")
    documented = text[text.index(BEGIN) : text.index(END) + len(END)]
    assert documented == table_markdown(RECORDS), "run: python docs/results/learning_checks_page.py"
