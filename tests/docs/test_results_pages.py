"""Every results page is what its script writes from the committed data files, and no page types a number by hand:
each page under docs/results/ comes from a template (``refpo_warp/studies/reports/results_page.py``) whose prose holds
no digit outside its fields and the phrases it allows, and its script, run with ``--check``, finds the page on disk
unchanged."""

import subprocess
from pathlib import Path

import pytest

from refpo_warp.studies.reports.results_page import (
    SUFFIX,
    load_template,
    render,
    script_command,
    templates,
    typed_numbers,
)
from refpo_warp.utils.errors import ConfigError
from refpo_warp.utils.paths import REPO_ROOT

RESULTS = REPO_ROOT / "docs" / "results"
TEMPLATES = templates(RESULTS)
# Pages that are not results pages of a script here: `refpo report`'s own output (written from a sweep's run dirs,
# whose per-run rows are committed beside it as runs.csv), and the sessions' diary.
NOT_TEMPLATED = ("report.md", "history.md")


def test_every_results_page_has_a_template():
    pages = {t.page for t in TEMPLATES}
    loose = [
        str(p.relative_to(REPO_ROOT))
        for p in sorted(RESULTS.rglob("*.md"))
        if not p.name.endswith(SUFFIX) and p not in pages and p.name not in NOT_TEMPLATED and "screen_" not in p.name
    ]
    assert not loose, f"results pages written by hand (give each a template and a script): {loose}"


@pytest.mark.parametrize("template", TEMPLATES, ids=lambda t: str(t.path.relative_to(RESULTS)))
def test_the_template_types_no_number(template):
    assert not typed_numbers(template), (
        f"{template.path}: digits in the prose (put them in a field the script computes, or allow the phrase):\n"
        + "\n".join(typed_numbers(template))
    )


@pytest.mark.parametrize("template", TEMPLATES, ids=lambda t: str(t.path.relative_to(RESULTS)))
def test_the_page_is_what_its_script_writes(template):
    command = script_command(template, check=True)
    done = subprocess.run(command, check=False, capture_output=True, text=True, cwd=REPO_ROOT, timeout=600)
    assert done.returncode == 0, (
        f"{' '.join(command[1:])} changes the page:\n{done.stdout[-4000:]}{done.stderr[-2000:]}"
    )


def write_template(tmp_path: Path, body: str, allow: str = "[]") -> Path:
    path = tmp_path / "page.template.md"
    path.write_text(f"<!-- page\nscript: make.py\nallow: {allow}\n-->\n{body}", encoding="utf-8")
    return path


def test_prose_digits_are_found_outside_fields_code_links_and_allowed_phrases(tmp_path):
    body = (
        "PPO {{ ppo }} at N = 10 (`seeds=[1,2]`), [page](docs/2.md)\n"
        "```\nrefpo sweep cpu_dmc seeds=[21,22]\n```\n<!-- 3 -->\n"
        "tuned 0.98 here\n"
    )
    template = load_template(write_template(tmp_path, body, '["N = 10"]'))
    assert typed_numbers(template) == ["tuned 0.98 here"]
    assert template.fields == ["ppo"]
    assert template.page == tmp_path / "page.md"


def test_a_field_without_a_value_or_a_value_without_a_field_is_refused(tmp_path):
    template = load_template(write_template(tmp_path, "{{ a }} and {{ b }}\n"))
    with pytest.raises(ConfigError, match=r"without a value \['b'\]"):
        render(template, {"a": 1})
    with pytest.raises(ConfigError, match=r"without a field \['c'\]"):
        render(template, {"a": 1, "b": 2, "c": 3})


def test_a_template_without_its_header_is_refused(tmp_path):
    path = tmp_path / "page.template.md"
    path.write_text("no header\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="header"):
        load_template(path)
