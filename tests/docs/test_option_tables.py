"""The option tables of the docs are made from the classes' option fields (refpo_warp/config/option_docs.py): a page
states the defaults, rules and meanings the code has, and every algorithm and model that declares options has a
table; docs/dmc.md's tables of the tasks and their env options are made from the task classes and cfgs."""

import inspect

from refpo_warp import algorithms, models
from refpo_warp.config.classes import resolve_class
from refpo_warp.config.option_docs import BLOCK, MADE, main, with_tables
from refpo_warp.utils.options import option_fields
from refpo_warp.utils.paths import REPO_ROOT

DOCS = REPO_ROOT / "docs"


def test_every_table_is_the_one_its_class_makes():
    stale = [
        str(page.relative_to(REPO_ROOT))
        for page in sorted(DOCS.rglob("*.md"))
        if with_tables(page.read_text(encoding="utf-8")) != page.read_text(encoding="utf-8")
    ]
    assert not stale, f"rewrite them: python -m refpo_warp.config.option_docs {' '.join(stale)}"


def _tabled() -> set[type]:
    return {
        resolve_class(m.group("name"))
        for page in DOCS.rglob("*.md")
        for m in BLOCK.finditer(page.read_text(encoding="utf-8"))
    }


def _declaring(package) -> set[type]:
    declaring = {cls for cls in vars(package).values() if inspect.isclass(cls) and option_fields(cls)}
    ours = {base for cls in declaring for base in cls.__mro__ if option_fields(base)}
    return {cls for cls in declaring | ours if cls.__module__.startswith("refpo_warp.")}  # not rsl_rl's


def test_every_algorithm_with_options_has_a_table():
    declaring = _declaring(algorithms)
    assert len(declaring) >= 5 and not declaring - _tabled(), f"without a table: {declaring - _tabled()}"


def test_every_model_with_options_has_a_table():
    declaring = _declaring(models)
    assert {models.FlowActor, models.ReinFlowActor, models.PhcMLPModel} <= declaring
    assert not declaring - _tabled(), f"without a table: {declaring - _tabled()}"


def test_a_changed_default_is_written_into_the_page(tmp_path, monkeypatch):
    from refpo_warp.algorithms import ReFPO

    page = tmp_path / "page.md"
    page.write_text("text\n<!-- options refpo_warp.algorithms:ReFPO -->\n| old |\n<!-- end options -->\nmore\n")
    assert main([str(page)]) == 0
    written = page.read_text()
    assert "| `reflow_coef` | 0.04 | a number in [0, 1e+06] | lambda, the weight of" in written
    assert "| old |" not in written and written.startswith("text\n") and written.endswith("more\n")
    monkeypatch.setattr(vars(ReFPO)["reflow_coef"], "default", 0.5)
    assert "| `reflow_coef` | 0.5 |" in with_tables(written)


def test_a_changed_actor_default_is_written_into_the_page(monkeypatch):
    from refpo_warp.models import FlowActor

    page = (DOCS / "algorithms.md").read_text(encoding="utf-8")
    assert "| `num_flow_steps` | 10 | an integer in [1, 1000] | N, Euler steps" in page
    monkeypatch.setattr(FlowActor.Options.__dataclass_fields__["num_flow_steps"], "default", 7)
    assert "| `num_flow_steps` | 7 |" in with_tables(page)


def _page_table(page: str, function: str) -> list[list[str]]:
    """The rows of the table a page's ``<!-- table <function> -->`` block holds, as cells."""
    (match,) = [m for m in MADE.finditer(page) if m.group("name") == function]
    lines = match.group("table").strip().splitlines()[2:]
    return [[c.strip() for c in line.strip("|").split(" | ")] for line in lines]


def test_the_dmc_options_table_gives_each_option_the_tasks_that_accept_it():
    """Against the registry (which tasks' cfg classes have the field), not the generator: an option of every DMC
    task is the family's, any other one task's own; the options every env has are not repeated unless the family
    gives one another default (action_transform: tanh)."""
    from dataclasses import fields

    from refpo_warp.envs.env_cfg import EnvCfg
    from refpo_warp.envs.registry import get_task, list_tasks
    from refpo_warp.tasks.dmc.cfg import DmcCfg

    dmc = [t for t in list_tasks() if t.startswith("dmc_")]
    accepting: dict[str, set[str]] = {}
    for task in dmc:
        for f in fields(get_task(task).cfg_class):
            accepting.setdefault(f.name, set()).add(task)
    everywhere = {f.name for f in fields(EnvCfg)} - set(option_fields(DmcCfg))
    expected = {
        name: "every DMC task" if tasks == set(dmc) else ", ".join(f"`{t}`" for t in sorted(tasks))
        for name, tasks in accepting.items()
        if name not in everywhere
    }
    rows = _page_table((DOCS / "dmc.md").read_text(encoding="utf-8"), "refpo_warp.tasks.dmc.doc_tables:options_table")
    assert {row[0].strip("`"): row[1] for row in rows} == expected
    assert expected["reset_bank_size"] == "`dmc_cheetah_run`" and expected["action_transform"] == "every DMC task"


def test_the_dmc_task_table_is_made_from_the_task_classes_and_model_files(monkeypatch):
    from refpo_warp.tasks.dmc.suite.cheetah_run import CheetahRun
    from refpo_warp.tasks.dmc.suite.walker_walk import WalkerWalk

    page = (DOCS / "dmc.md").read_text(encoding="utf-8")
    rows = {r[0]: r[1:] for r in _page_table(page, "refpo_warp.tasks.dmc.doc_tables:tasks_table")}
    # Playground's sizes and control steps (ctrl_dt / sim_dt: cheetah 0.01 / 0.01, walker 0.025 / 0.0025)
    assert rows["`dmc_cheetah_run`"][:3] == ["17", "6", "0.01 = 0.01 x 1"]
    assert rows["`dmc_walker_walk`"][:3] == ["24", "6", "0.025 = 0.0025 x 10"]
    assert rows["`dmc_point_mass_wall` (ours)"][1] == "2" and len(rows) == 11
    monkeypatch.setattr(CheetahRun, "reward_summary", "a new reward")
    monkeypatch.setattr(WalkerWalk, "num_obs", 25)
    made = with_tables(page)
    assert "| `dmc_cheetah_run` | 17 | 6 | 0.01 = 0.01 x 1 | a new reward |" in made
    assert "| `dmc_walker_walk` | 25 | 6 |" in made
