"""Where SIGINT and SIGTERM act: held while a block runs, then run where the block chooses.

Python runs a signal's handler in the main thread at the next instruction after the signal lands, wherever that
is; Ctrl-C's handler raises KeyboardInterrupt, and so does the export command's for SIGTERM. Two places here must
not be interrupted just anywhere:
- the export's process pool (platform_tools.dataset.engines). A raise in the middle of code that takes several
  locks in turn leaves some of them taken: concurrent.futures.wait takes the lock of every pending future, one
  after another, and a SIGTERM that landed there left one taken by the main thread; the executor's manager
  thread then waited for it forever, and the process with it at exit (an export that SIGTERM never ended, seen
  in CI; tests/dataset/interrupt_probe.py makes it happen on purpose). The pool holds both signals while it
  waits and runs them between two tasks; the export holds them while it writes a marker, the manifest or the
  index, so that each is written whole;
- boson-config's transaction (platform_tools.boson.transaction): a camera must not be left half-configured, so
  a signal ends the step in progress and then every camera is put back, as after a failure; the signal's
  default action (SIGTERM's: end the process at once) is not taken.

:func:`held` is the one tool: while its block runs, each of the two signals only records its number (and calls
``wake``, so that a wait can end at once, or a line can say what happens next); the block runs what came with
the function it is given (:class:`Held`), or reads and clears ``came`` to act on it itself, and whatever is still
held when the block ends is raised again then, with the handlers restored. The handlers run are the ones in place
when the block started: a signal at its default still ends the process when delivered, and an ignored one (a
background job's SIGINT) is left ignored: it is not even recorded.
"""
from __future__ import annotations

import signal
import threading
from typing import Callable

#: the signals held: Ctrl-C, and what `docker stop`, systemd and batch schedulers send
HELD_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Held:
    """The signals that came while a :func:`held` block ran (their numbers, first first) and the handlers they
    have outside it. Calling it runs the first one's handler now: :meth:`__call__`."""

    def __init__(self, wake: Callable[[int], None] | None):
        self.came: list[int] = []           #: signal numbers, in the order they came
        self._wake = wake
        self._outer: dict[int, object] = {}     #: signal number -> its handler outside the block
        self._active = False

    def _record(self, signum: int, frame) -> None:
        self.came.append(signum)
        if self._wake is not None:
            self._wake(signum)

    def _install(self) -> None:
        for sig in HELD_SIGNALS:
            if sig not in self._outer and signal.getsignal(sig) is signal.SIG_IGN:
                continue                    # ignored before the block: left ignored
            outer = signal.signal(sig, self._record)
            self._outer.setdefault(sig, outer)
        self._active = True

    def _restore(self) -> None:
        if self._active:
            for sig, handler in self._outer.items():
                signal.signal(sig, handler)
            self._active = False

    def __call__(self) -> None:
        """Run the handler of the first signal held so far, here (the others that came with it are dropped: one
        interrupt is one interrupt); what it raises goes on from here, and the block goes on holding. Nothing
        when no signal came, or outside the main thread."""
        if not self.came or not self._active:
            return
        sig = self.came[0]
        self.came.clear()
        self._restore()
        try:
            # raise_signal runs the handler before it returns, in this thread (the main one): KeyboardInterrupt
            # raised here; a default SIGTERM ends the process, as it would have
            signal.raise_signal(sig)
        finally:
            self._install()


class held:
    """``with held(wake) as deliver:`` SIGINT and SIGTERM recorded instead of run while the block runs (in the main
    thread, the only one where Python runs handlers; elsewhere the block changes nothing). ``wake(signum)`` is
    called in the handler as each comes: it must be safe there (``queue.SimpleQueue.put``, documented as
    reentrant, is; printing a line is, where the code the signal lands in does not print to the same stream).
    ``deliver()`` runs the first held one's handler where the block calls it (:meth:`Held.__call__`); on leaving
    the block the handlers are restored and the first signal still held is raised again, so its handler runs then.
    Blocks nest: an inner block's leftover signal goes to the outer block's record."""

    def __init__(self, wake: Callable[[int], None] | None = None):
        self._held = Held(wake)

    def __enter__(self) -> Held:
        if threading.current_thread() is threading.main_thread():
            self._held._install()
        return self._held

    def __exit__(self, *exc) -> None:
        h = self._held
        h._restore()
        if h.came:
            sig = h.came[0]
            h.came.clear()
            signal.raise_signal(sig)
