"""A run trained in pieces: ``stop_after_iterations`` / ``stop_after_minutes`` end a ``refpo train`` call early at a
checkpoint, and ``resume=true`` continues it. Every checkpoint holds the run's state (``refpo_warp.runner.run_state``:
generators and env), so a run advanced call by call ends bit-identical to one trained in a single call.

A piece ends only between iterations (after the iteration's periodic evaluation, if one is due), the one point where
the whole state is in the env's arrays, the generators and the checkpoint. With ``stop_after_minutes`` the run learns
one iteration per chunk (which changes nothing it computes) and stops when the next iteration, judged by the longest
one so far, would end past the limit; every call learns at least one iteration.
"""

from __future__ import annotations

import time


class PieceEnd:
    """Where this call's piece of a run ends: after ``iterations`` iterations or before ``minutes`` pass."""

    def __init__(self, iterations: int | None, minutes: float | None, start: int, started: float) -> None:
        self.iterations, self.minutes, self.start = iterations, minutes, start
        self.started = started  # time.monotonic() when the call began
        self.longest = 0.0
        self._chunk_started = self.started

    def chunk_end(self, it: int, end: int) -> int:
        """The end of the chunk from ``it``: ``end``, or sooner where the piece may end."""
        self._chunk_started = time.monotonic()
        if self.iterations is not None:
            end = min(end, self.start + self.iterations)
        if self.minutes is not None:
            end = min(end, it + 1)  # the clock is read after every iteration
        return end

    def reason(self, it: int) -> str | None:
        """Why the piece ends before iteration ``it`` (None: it goes on); called after each chunk."""
        now = time.monotonic()
        self.longest = max(self.longest, now - self._chunk_started)
        if self.iterations is not None and it >= self.start + self.iterations:
            return f"stop_after_iterations={self.iterations}"
        if self.minutes is not None and now - self.started + self.longest > 60 * self.minutes:
            return f"stop_after_minutes={self.minutes:g}: the next iteration would end past it"
        return None
