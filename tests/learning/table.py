"""The learning checks' table (``docs/results/learning_checks.md``) from their measured records, and the rule each bound
must obey (``tests/learning/checks.py``): strictly beyond the null control's best run, and at most halfway from it to
the learning runs' worst."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from checks import CHECKS, Bound, LearningCheck  # tests/learning/checks.py

LEARNING_RUNS = {1: [1, 2, 3, 4, 5], 2: [1, 2, 3]}  # torch threads -> seeds
NULL_RUNS = [1, 2, 3]  # seeds, one thread
BEGIN, END = "<!-- table: begin (python tests/learning/measure.py table) -->", "<!-- table: end -->"


@dataclass
class BoundStanding:
    """Where one bound sits between the null control's best run and the learning runs' worst."""

    bound: Bound
    learning: list[tuple[int, int, float]]  # (threads, seed, value)
    null: list[tuple[int, float]]  # (seed, value)

    @property
    def worst(self) -> tuple[int, int, float]:
        pick = min if self.bound.op == ">=" else max
        return pick(self.learning, key=lambda r: r[2])

    @property
    def null_best(self) -> tuple[int, float]:
        pick = max if self.bound.op == ">=" else min
        return pick(self.null, key=lambda r: r[1])

    @property
    def halfway(self) -> float:
        return (self.worst[2] + self.null_best[1]) / 2

    def problems(self) -> list[str]:
        """Why the bound breaks the rule (empty: it obeys it). A claim bound is not placed between the runs: every
        learning run must meet it, and the null control may."""
        b, worst, null, half = self.bound, self.worst[2], self.null_best[1], self.halfway
        sign = 1.0 if b.op == ">=" else -1.0
        if b.claim:
            return [] if sign * (worst - b.value) >= 0 else [f"{b}: the claim fails in a learning run ({worst:.4g})"]
        out = []
        if sign * (b.value - null) <= 0:
            out.append(f"{b}: not beyond the null control's best ({null:.4g})")
        if sign * (b.value - half) > 1e-12:
            out.append(
                f"{b}: beyond halfway ({half:.4g}) from the null control's best ({null:.4g}) to the learning "
                f"runs' worst ({worst:.4g})"
            )
        return out


def standings(check: LearningCheck, records: list[dict]) -> tuple[list[BoundStanding], list[str]]:
    """Each bound's standing over the runs the rule asks for, and the runs missing from the records."""
    learning = {
        (r["threads"], r["seed"]): check.statistics(r) for r in records if r["check"] == check.name and not r["null"]
    }
    null = {
        r["seed"]: check.statistics(r) for r in records if r["check"] == check.name and r["null"] and r["threads"] == 1
    }
    missing = [
        f"{check.name} learning, {t} thread(s), seed {s}"
        for t, seeds in LEARNING_RUNS.items()
        for s in seeds
        if (t, s) not in learning
    ]
    missing += [f"{check.name} null control, seed {s}" for s in NULL_RUNS if s not in null]
    out = [
        BoundStanding(
            b,
            [(t, s, stats[b.statistic]) for (t, s), stats in sorted(learning.items())],
            [(s, stats[b.statistic]) for s, stats in sorted(null.items())],
        )
        for b in check.bounds
    ]
    return out, missing


def fmt(x: float) -> str:
    return f"{x:.3g}" if abs(x) < 1000 else f"{x:.0f}"


def check_rows(check: LearningCheck, records: list[dict]) -> list[str]:
    rows = []
    for s in standings(check, records)[0]:
        if not s.learning or not s.null:
            continue
        t, seed, worst = s.worst
        nseed, null = s.null_best
        halfway, to_null = ("claim", "-") if s.bound.claim else (fmt(s.halfway), fmt(abs(s.bound.value - null)))
        rows.append(
            f"| {check.name} | `{s.bound}` | {fmt(worst)} (seed {seed}, {t} thr.) | "
            f"{fmt(min(v for *_, v in s.learning))}-{fmt(max(v for *_, v in s.learning))} | "
            f"{fmt(null)} (seed {nseed}) | {halfway} | {fmt(abs(worst - s.bound.value))} | "
            f"{to_null} |"
        )
    return rows


def per_seed_rows(check: LearningCheck, records: list[dict]) -> list[str]:
    mine = sorted((r for r in records if r["check"] == check.name), key=lambda r: (r["null"], r["threads"], r["seed"]))
    rows = []
    for r in mine:
        stats = check.statistics(r)
        passed = all(b.holds(stats) for b in check.bounds)
        values = ", ".join(f"{k} {fmt(v)}" for k, v in stats.items())
        rows.append(
            f"| {check.name} | {'null control' if r['null'] else 'learning'} | {r['threads']} | {r['seed']} | "
            f"{values} | {'pass' if passed else 'fail'} | {r['cpu']} | {r['wall_s']:.0f} |"
        )
    return rows


def table_markdown(records: list[dict]) -> str:
    cpus = sorted({r["cpu"] for r in records})
    lines = [
        BEGIN,
        "",
        (
            "| check | bound | learning runs' worst | learning range | null control's best | halfway | "
            "margin to learning | margin to null |"
        ),
        "|---|---|---|---|---|---|---|---|",
    ]
    for check in CHECKS.values():
        lines += check_rows(check, records)
    lines += [
        "",
        (
            "Per run (statistics as the check reads them; wall seconds of the run, the initial evaluation "
            "included, on a shared 2-core machine):"
        ),
        "",
        "| check | runs | torch threads | seed | statistics | bound | CPU | wall s |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for check in CHECKS.values():
        lines += per_seed_rows(check, records)
    lines += ["", f"CPUs of these runs: {'; '.join(cpus)} (2 cores each).", "", END]
    return "\n".join(lines)


def write_table(records: list[dict], path: Path) -> None:
    """Replace the generated part of ``path`` (between the BEGIN and END markers) with the table of ``records``."""
    text = path.read_text(encoding="utf-8")
    if BEGIN not in text or END not in text:
        raise SystemExit(f"{path}: no '{BEGIN}' ... '{END}' markers to write the table between")
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    path.write_text(head + table_markdown(records) + tail, encoding="utf-8")
