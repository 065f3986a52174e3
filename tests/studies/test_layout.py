"""The study packages import one way (``refpo_warp/studies/__init__.py``): grid/ below ray/, both below backends.py,
which sweep.py and tuning/ use, and reports/ on top (it reproduces tuning trials' commands); a package imports only
the ones below it."""

from refpo_warp.utils.layering import first_party_modules, import_graph

ORDER = ["grid", "ray", "backends", "sweep", "tuning", "reports"]  # bottom to top; sweep and tuning never meet


def study_part(module: str) -> str | None:
    parts = module.split(".")
    return parts[2] if len(parts) > 2 and parts[:2] == ["refpo_warp", "studies"] else None


def test_the_study_packages_import_one_way():
    graph = import_graph(first_party_modules())
    parts = {study_part(m) for m in graph} - {None}
    assert parts == set(ORDER), f"studies/ holds {sorted(parts)}; ORDER names {ORDER}"
    edges = {
        (study_part(m), study_part(t))
        for m, targets in graph.items()
        for t in targets
        if study_part(m) and study_part(t) and study_part(m) != study_part(t)
    }
    upward = sorted((a, b) for a, b in edges if ORDER.index(b) > ORDER.index(a) or {a, b} == {"sweep", "tuning"})
    assert not upward, f"imports into a higher study package: {upward}"
    assert ("tuning", "backends") in edges and ("sweep", "backends") in edges  # both run their runs the same way
