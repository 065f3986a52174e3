"""One clear message and a documented exit code for every failure of a command (``docs/cli.md``).

Exit codes: 0 done; 1 unexpected error (the message, and the file holding the full traceback); 2 invalid command
line or config (bad option value, unknown key, a resume that would change the run, a run dir that cannot be used);
3 training stopped on a non-finite loss; 4 an input file is missing, damaged or refused (checkpoint, motion file,
saved config, progress log); 5 the system refused (disk full, permission denied, out of memory, no OpenGL platform
for rendering); 130 interrupted. A sweep with a failed run exits 1 (its summary names the run and its log).
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
import traceback
from collections.abc import Callable
from pathlib import Path

from refpo_warp.utils.errors import (
    EXIT_BAD_FILE,
    EXIT_INTERRUPTED,
    EXIT_NONFINITE,
    EXIT_OK,
    EXIT_SYSTEM,
    EXIT_UNEXPECTED,
    EXIT_USAGE,
    ConfigError,
    DataFileError,
    NonFiniteLossError,
    SystemRefusedError,
)

ERROR_LOG = "error.log"


def run_guarded(fn: Callable[[], int | None]) -> int:
    """Run ``fn``; turn every failure into one message on stderr and its exit code (see the module docstring). The
    exit code of a run that ends: ``fn``'s, when it returns one (a sweep with a failed run), else 0."""
    try:
        code = fn()
    except ConfigError as err:
        return _fail(f"error: {err}", EXIT_USAGE)
    except DataFileError as err:
        return _fail(f"error: {err}", EXIT_BAD_FILE)
    except NonFiniteLossError as err:
        return _fail(non_finite_message(err), EXIT_NONFINITE)
    except KeyboardInterrupt as err:
        latest = _latest(err)
        kept = f" (newest: {latest})" if latest else ""
        message = f"interrupted; checkpoints written so far are intact{kept}; resume=true continues"
        return _fail(message, EXIT_INTERRUPTED)
    except SystemRefusedError as err:
        return _fail(f"error: {err}", EXIT_SYSTEM)
    except MemoryError:
        return _fail("error: out of memory; lower num_envs, runner.num_steps_per_env or the network sizes", EXIT_SYSTEM)
    except OSError as err:
        where = f"{err.filename}: " if err.filename else ""
        return _fail(f"error: {where}{err.strerror or err}", EXIT_SYSTEM)
    except Exception as err:  # (the last resort: a message and the traceback in a file)
        if type(err).__name__ == "OutOfMemoryError":  # torch's CUDA out-of-memory error
            return _fail(
                f"error: out of GPU memory ({str(err).splitlines()[0]}); lower num_envs or the network sizes",
                EXIT_SYSTEM,
            )
        log = write_traceback(err)
        summary = " ".join(str(err).split())[:500] or "(no message)"
        return _fail(
            f"error: unexpected {type(err).__name__}: {summary}\nThis is a bug or a case refpo_warp does not "
            f"foresee; the full traceback is in {log}",
            EXIT_UNEXPECTED,
        )
    return EXIT_OK if code is None else code


def non_finite_message(err: NonFiniteLossError) -> str:
    """What stopped, whether a checkpoint survives, and a command that continues (or restarts) the run."""
    run_dir, checkpoint = getattr(err, "run_dir", None), getattr(err, "checkpoint", None)
    lr = getattr(err, "learning_rate", None)
    smaller = f"a learning rate below {lr:g}" if lr else "a smaller learning rate"
    lines = [f"error: training stopped: {err}"]
    if checkpoint is not None:
        lines.append(
            f"The checkpoints written before the failure are intact; the newest is {checkpoint}. To continue "
            f"from it with {smaller}: refpo train run_dir={run_dir} resume=true "
            f"algorithm.learning_rate=<value>"
        )
    else:
        where = f" in {run_dir}" if run_dir else ""
        lines.append(
            f"No checkpoint was written before the failure{where}, so there is nothing to resume; start the "
            f"run again with {smaller} (algorithm.learning_rate=<value>) or, for flow policies, "
            f"algorithm.log_ratio_clip=<value>"
        )
    return "\n".join(lines)


def write_traceback(err: BaseException) -> Path | str:
    """Write the full traceback to ``<run dir>/error.log`` (or a temp file when no run dir exists); its path."""
    text = "".join(traceback.format_exception(type(err), err, err.__traceback__))
    run_dir = getattr(err, "run_dir", None)
    candidates = [Path(run_dir) / ERROR_LOG] if run_dir and Path(run_dir).is_dir() else []
    stamp = time.strftime("%Y%m%d-%H%M%S")
    candidates.append(Path(tempfile.gettempdir()) / f"refpo_warp-error-{stamp}-{os.getpid()}.log")
    for path in candidates:
        try:
            from refpo_warp.utils.atomic_files import write_text

            write_text(path, text)
            return path
        except OSError:
            continue
    print(text, file=sys.stderr)  # nowhere to write it: better on the screen than lost
    return "the output above"


def _latest(err: BaseException):
    run_dir = getattr(err, "run_dir", None)
    if run_dir is None:
        return None
    from refpo_warp.runner.checkpoints import latest_checkpoint

    return latest_checkpoint(run_dir)


def _fail(message: str, code: int) -> int:
    print(message, file=sys.stderr, flush=True)
    return code
