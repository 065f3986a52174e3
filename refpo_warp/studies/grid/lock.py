"""One process per study folder (a sweep dir, a tuning folder): a second one would clear the first one's run dirs."""

from __future__ import annotations

import fcntl
from pathlib import Path

from refpo_warp.utils.errors import ConfigError


class SweepLock:
    """Held while the file ``<out_dir>/.lock`` is open; released by ``release`` or when the process ends."""

    def __init__(self, out_dir: Path) -> None:
        out_dir.mkdir(parents=True, exist_ok=True)
        self.file = open(out_dir / ".lock", "w")  # noqa: SIM115 (held open: the lock lasts while the file is open)
        try:
            fcntl.flock(self.file, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError as err:
            self.file.close()
            raise ConfigError(f"Another sweep is running in {out_dir} (lock {out_dir / '.lock'})") from err

    def release(self) -> None:
        fcntl.flock(self.file, fcntl.LOCK_UN)
        self.file.close()
