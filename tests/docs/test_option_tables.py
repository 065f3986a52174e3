"""The option tables of the docs are made from the classes' option fields (refpo_warp/config/option_docs.py): a page
states the defaults, rules and meanings the code has, and every algorithm and model that declares options has a
table."""

import inspect

from refpo_warp import algorithms, models
from refpo_warp.config.classes import resolve_class
from refpo_warp.config.option_docs import BLOCK, main, with_tables
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
