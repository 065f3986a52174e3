"""Where each committed run under ``docs/results/`` comes from, checked against today's code.

``docs/results/provenance.yaml`` (the registry) names, for every committed results folder, the command that makes
its runs, as the folder's page gives it::

    entries:
      - folder: fpo_pp/runs                     # under docs/results/
        page: fpo_pp/README.md                  # the page that gives the command
        command: refpo sweep cpu_fpo_pp methods=[fpo_pp,refpo_pp]
        made_at: "f11a28a"                      # only where today's command resolves to another config: the
        difference:                             # commit(s) that added the runs, and each differing key as
          algorithm.learning_rate: [0.0001, 0.00147]   # [the runs' config.yaml, today's command]

A command is ``refpo sweep <name or spec file> [key=value ...]`` (its runs at ``<folder>/<task>/<label>/seed<k>``),
``refpo tune <name or file>`` with ``trials:`` naming the study's ``trials.csv`` (each trial's runs at
``<folder>/<label>/trial<NN>/<task>``, at the trial's values over the profiles) or ``refpo train`` / ``refpo pretrain
key=value ...`` (one run: the folder itself). Commands resolve at ``device=cpu`` unless they say otherwise (the
committed runs were made on CPU machines), each (task, method) cell once. A committed run's ``config.yaml`` is
compared with the config its command resolves to on today's code (``resolve_config``, as ``refpo train`` does)
without the keys that do not change what a run computes (``comparable``); a key the saved config lacks (added to the
code since) is a difference, shown as ``(absent)``. ``tests/docs/test_result_provenance.py`` requires every committed
run to be made by exactly one entry, each entry's recorded difference to be exactly the current one and its
``made_at`` the commit(s) that added its runs (``git log``); ``docs/results/provenance_page.py`` writes the page
(``docs/results/provenance.md``).
"""

from __future__ import annotations

import csv
import functools
import json
import re
import shlex
import subprocess
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from refpo_warp.config.dotted import flatten, parse_overrides
from refpo_warp.config.yaml_files import load_yaml
from refpo_warp.studies.grid.spec import computed_part, device_type
from refpo_warp.utils.errors import ConfigError, unknown
from refpo_warp.utils.paths import REPO_ROOT

RESULTS = REPO_ROOT / "docs" / "results"
REGISTRY = RESULTS / "provenance.yaml"
RUN_CONFIG = "config.yaml"
ABSENT = "(absent)"  # a key one of the two configs does not have
# Options whose "auto" a run's config.yaml records as what it decided (refpo pretrain: from the dataset), so a
# command left at auto makes a run saved with any of these values.
DECIDED_FROM_AUTO = {"pretrain.dataset_actions": ("pre_squash", "env_units")}
ENTRY_KEYS = ("folder", "page", "command", "trials", "made_at", "difference")
COMMANDS = ("sweep", "tune", "train", "pretrain")
_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml where installed: 205 saved configs read fast
_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


@dataclass(frozen=True)
class Entry:
    """One results folder and the command that makes its runs (with the recorded drift, if any)."""

    folder: str
    command: str
    page: str | None = None
    trials: str | None = None  # a tuning study's trials.csv (under docs/results/): each trial's values
    made_at: tuple[str, ...] = ()  # the commit(s) that added the runs, where they differ from today's command
    difference: dict[str, list] | None = None

    @property
    def path(self) -> Path:
        return RESULTS / self.folder


@dataclass
class Checked:
    """What today's code says about an entry: its runs (committed of made) and how their configs differ."""

    entry: Entry
    made: list[str]  # run folders the command makes, relative to the entry's folder ('' for a single run)
    committed: list[str]  # of those, the ones committed (with a config.yaml)
    differences: dict[str, dict[str, list]] = field(default_factory=dict)  # committed run -> key -> [saved, today]

    @property
    def difference(self) -> dict[str, list]:
        """The one difference every committed run of the entry shares (``{}``: they match today's command)."""
        found = {yaml.safe_dump(d, sort_keys=True) for d in self.differences.values()}
        if len(found) > 1:
            lines = [f"  {run or '.'}: {d}" for run, d in self.differences.items()]
            raise ConfigError(
                f"{self.entry.folder}: its runs differ from today's command in different ways (split the entry "
                "by command):\n" + "\n".join(lines)
            )
        return next(iter(self.differences.values()), {})

    def problems(self) -> list[str]:
        """Why the registry's record of this entry is not what today's code says (empty: it is)."""
        out = []
        if not self.committed:
            out.append(f"{self.entry.folder}: `{self.entry.command}` makes none of the committed runs")
        try:
            current = self.difference
        except ConfigError as err:
            return [*out, str(err)]
        recorded = self.entry.difference or {}
        if current != recorded:
            out.append(
                f"{self.entry.folder} (`{self.entry.command}`): the runs' config.yaml differs from today's command "
                f"by {current or 'nothing'}, the registry records {recorded or 'nothing'}"
            )
        if current and not self.entry.made_at:
            out.append(f"{self.entry.folder}: its runs differ from today's command; record made_at: <commit>")
        if not current and self.entry.made_at:
            out.append(f"{self.entry.folder}: its runs match today's command; drop made_at")
        return out


def read_registry(path: Path = REGISTRY) -> list[Entry]:
    data = load_yaml(path)
    entries = data.get("entries") if isinstance(data, dict) else None
    if not isinstance(entries, list) or not entries:
        raise ConfigError(f"{path}: 'entries' must be a list of {{folder, command, page, made_at, difference}}")
    out = []
    for item in entries:
        if not isinstance(item, dict) or "folder" not in item or "command" not in item:
            raise ConfigError(f"{path}: each entry needs 'folder' and 'command', got {item!r}")
        for key in item:
            if key not in ENTRY_KEYS:
                raise unknown(f"key of an entry in {path}", key, ENTRY_KEYS)
        made_at = item.get("made_at") or []
        made_at = [made_at] if not isinstance(made_at, list) else made_at
        if not all(isinstance(c, str) and re.fullmatch(r"[0-9a-f]{7,40}", c) for c in made_at):
            raise ConfigError(
                f"{path}: {item['folder']}: made_at is a commit hash or a list of them, quoted (YAML reads 4e63504 as "
                f"a number), got {item.get('made_at')!r}"
            )
        out.append(
            Entry(
                str(item["folder"]).rstrip("/"),
                " ".join(str(item["command"]).split()),
                None if item.get("page") is None else str(item["page"]),
                None if item.get("trials") is None else str(item["trials"]),
                tuple(made_at),
                item.get("difference"),
            )
        )
    return out


def read_config(path: Path) -> dict:
    """A run's saved ``config.yaml`` (written by ``dump_config``)."""
    data = yaml.load(path.read_text(encoding="utf-8"), Loader=_LOADER)
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping at the top level")
    return data


def committed_runs(root: Path = RESULTS) -> list[Path]:
    """Every committed run folder under ``root``: a folder with a ``config.yaml``."""
    return sorted(p.parent for p in root.rglob(RUN_CONFIG))


# ------------------------------------------------------------------------------------------------ comparing
def comparable(cfg: dict) -> dict[str, Any]:
    """A run config as the flat dotted keys that change what the run computes (``computed_part``, ``fingerprint``'s
    view)."""
    plain = yaml.dump(computed_part(cfg), Dumper=_DUMPER)  # tuples as lists
    return flatten(yaml.load(plain, Loader=_LOADER))


def config_difference(saved: dict, today: dict) -> dict[str, list]:
    """``key: [saved, today]`` for every key of ``comparable`` whose value differs as ``fingerprint`` tells values
    apart (``1`` is not ``1.0``; ``(absent)`` where one config lacks the key), in key order; ``{}`` when the two
    configs compute the same run."""
    old, new = comparable(saved), comparable(today)
    out = {}
    for key in sorted(set(old) | set(new)):
        pair = [old.get(key, ABSENT), new.get(key, ABSENT)]
        if key in DECIDED_FROM_AUTO and pair[1] == "auto" and pair[0] in DECIDED_FROM_AUTO[key]:
            continue  # refpo pretrain saves what auto decided from the dataset: the same run
        if json.dumps(pair[0], sort_keys=True) != json.dumps(pair[1], sort_keys=True):
            out[key] = pair
    return out


# ------------------------------------------------------------------------------------------------ commands
def _source(name: str) -> str:
    """A sweep or tuning file named by path is relative to the repository root; a bare name is a shipped one."""
    return str(REPO_ROOT / name) if name.endswith((".yaml", ".yml")) and not Path(name).is_absolute() else name


@functools.cache
def _resolve(kind: str, args: tuple[str, ...]) -> dict:
    """The config ``refpo train`` (or ``refpo pretrain``) resolves ``args`` to, at ``device=cpu`` unless they say
    otherwise; once per process for the same arguments (entries share cells). Callers copy before changing it."""
    from refpo_warp.config.resolve import resolve_config

    flat = parse_overrides(list(args))
    device = str(flat.setdefault("device", "cpu"))
    if kind == "pretrain":
        from refpo_warp.demonstrations.pretrain_run import pretrain_config

        return pretrain_config(flat).cfg
    return resolve_config(flat, device_type=device_type(device))


@dataclass(frozen=True)
class Planned:
    """One run a command makes: what resolves its config (its seed apart: seeds differ only in ``seed``)."""

    kind: str  # train | pretrain
    args: tuple[str, ...]  # without seed= and run_dir=
    seed: int | None  # None: the command's own (a single run)

    def config(self) -> dict:
        cfg = _resolve(self.kind, self.args)
        return cfg if self.seed is None else {**cfg, "seed": self.seed}


def command_runs(entry: Entry) -> dict[str, Planned]:
    """Run folder (relative to the entry's folder; ``''``: the folder itself) -> how today's code makes that run."""
    words = shlex.split(entry.command)
    if len(words) < 2 or words[0] != "refpo" or words[1] not in COMMANDS:
        raise ConfigError(f"{entry.folder}: a command is 'refpo <{'|'.join(COMMANDS)}> ...', got '{entry.command}'")
    kind, rest = words[1], words[2:]
    if kind in ("train", "pretrain"):
        return {"": Planned(kind, tuple(rest), None)}
    if not rest:
        raise ConfigError(f"{entry.folder}: 'refpo {kind}' needs the sweep or tuning it runs")
    if kind == "sweep":
        from refpo_warp.studies.grid.spec import load_sweep

        sweep = load_sweep(_source(rest[0]), rest[1:])
        runs, device, out_dir = sweep.runs, sweep.device, sweep.out_dir
    else:
        runs, device, out_dir = _trial_runs(entry, rest)
    out = {}
    for run in runs:
        args = tuple(a for a in run.args if not a.startswith(("seed=", "run_dir=")))
        out[run.run_dir.relative_to(out_dir).as_posix()] = Planned("train", (*args, f"device={device}"), run.seed)
    return out


def _trial_runs(entry: Entry, args: list[str]) -> tuple[list, str, Path]:
    """The runs of every trial in the study's ``trials.csv`` (the entry's ``trials``), at the trial's values."""
    from refpo_warp.studies.tuning.spec import load_tuning

    if not entry.trials:
        raise ConfigError(f"{entry.folder}: a 'refpo tune' entry names the study's trials.csv (trials: <file>)")
    with (RESULTS / entry.trials).open(encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    tuning = load_tuning(_source(args[0]), args[1:])
    methods = {m.label: m for m in tuning.methods}
    runs = []
    for row in rows:
        if row["method"] not in methods:
            raise unknown(f"method of {entry.trials}", row["method"], list(methods))
        method = methods[row["method"]]
        values = {d.key: yaml.safe_load(row[d.key]) for d in method.space}
        runs += tuning.trial_runs(method, int(row["trial"]), values)
    return runs, tuning.device, tuning.out_dir


def check(entry: Entry) -> Checked:
    """Compare every committed run of the entry with the config its command resolves to today."""
    planned = command_runs(entry)
    made = sorted(planned)
    committed = [run for run in made if (entry.path / run / RUN_CONFIG).exists()]
    checked = Checked(entry, made, committed)
    for run in committed:
        saved = read_config(entry.path / run / RUN_CONFIG)
        checked.differences[run] = config_difference(saved, planned[run].config())
    return checked


def adding_commits(checked: Checked) -> list[str] | None:
    """The commits (short hashes, oldest first) that added the entry's committed ``config.yaml`` files, by
    ``git log``; ``None`` where the history cannot say (no git, a shallow clone)."""
    files = [str((checked.entry.path / run / RUN_CONFIG).relative_to(REPO_ROOT)) for run in checked.committed]
    if not files:
        return []
    try:
        shallow = subprocess.run(
            ["git", "rev-parse", "--is-shallow-repository"], cwd=REPO_ROOT, capture_output=True, text=True, check=True
        )
        if shallow.stdout.strip() != "false":
            return None
        done = subprocess.run(
            ["git", "log", "--reverse", "--no-renames", "--format=%h", "--diff-filter=A", "--", *files],
            cwd=REPO_ROOT,
            capture_output=True,
            text=True,
            check=True,
        )
    except (OSError, subprocess.CalledProcessError):
        return None
    return list(dict.fromkeys(done.stdout.split()))


def same_commits(recorded: tuple[str, ...], found: list[str]) -> bool:
    """Whether the recorded commits are the found ones (abbreviations of either length)."""
    return len(recorded) == len(found) and all(any(a.startswith(b) or b.startswith(a) for b in found) for a in recorded)


def check_all(entries: list[Entry] | None = None) -> list[Checked]:
    return [check(e) for e in (read_registry() if entries is None else entries)]


def unclaimed(checked: list[Checked], root: Path = RESULTS) -> tuple[list[str], list[str]]:
    """(committed run folders no entry makes, those two or more entries make), relative to ``root``."""
    claims: dict[Path, int] = {}
    for c in checked:
        for run in c.committed:
            path = (c.entry.path / run).resolve()
            claims[path] = claims.get(path, 0) + 1
    runs = [p.resolve() for p in committed_runs(root)]
    loose = [str(p.relative_to(root.resolve())) for p in runs if p not in claims]
    twice = [str(p.relative_to(root.resolve())) for p in runs if claims.get(p, 0) > 1]
    return loose, twice
