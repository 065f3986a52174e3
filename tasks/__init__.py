"""Task families. Importing this package registers every task id (cheaply: env modules load on first use)."""

from tasks import gridworld  # noqa: F401

for _family in ("dmc", "humanoid"):
    try:
        __import__(f"tasks.{_family}")
    except ModuleNotFoundError as _err:  # a family that is not in this checkout yet
        if _err.name != f"tasks.{_family}":
            raise
