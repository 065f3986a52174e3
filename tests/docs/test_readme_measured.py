"""The README's measured parts are what ``docs/results/measured.py`` writes from the committed data files: every
block between its ``<!-- measured: NAME -->`` and ``<!-- measured: end -->`` markers, run with ``--check``, comes
out unchanged."""

import subprocess
import sys

from refpo_warp.utils.paths import REPO_ROOT

SCRIPT = REPO_ROOT / "docs" / "results" / "measured.py"


def test_the_readme_measured_blocks_are_what_the_data_says():
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--check"],
        check=False,
        capture_output=True,
        text=True,
        cwd=REPO_ROOT,
        timeout=600,
    )
    assert done.returncode == 0, (
        f"python {SCRIPT.relative_to(REPO_ROOT)} changes README.md (run it to write the blocks):\n"
        + (done.stdout + done.stderr)[-4000:]
    )


def test_every_block_has_its_markers():
    sys.path.insert(0, str(SCRIPT.parent))
    try:
        import measured
    finally:
        sys.path.remove(str(SCRIPT.parent))
    text = (REPO_ROOT / "README.md").read_text(encoding="utf-8")
    assert sorted(m.group(2) for m in measured.BLOCK.finditer(text)) == sorted(measured.BLOCKS)


def test_seeds_are_written_as_runs_of_consecutive_numbers():
    sys.path.insert(0, str(SCRIPT.parent))
    try:
        import measured
    finally:
        sys.path.remove(str(SCRIPT.parent))
    assert measured.seeds_text([3, 1, 2, 21, 22, 5]) == "1-3, 5, 21-22"
    assert measured.seeds_text([11]) == "11"
