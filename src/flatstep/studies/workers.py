"""Process-pool workers that end with their parent: :func:`die_with_parent`, the initializer of batch pools."""
from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time

from .batch_file import pid_alive

#: ``prctl`` option: the signal a process receives when its parent dies (linux/prctl.h).
_PR_SET_PDEATHSIG = 1


def die_with_parent(parent: int) -> None:
    """Process-pool initializer: end this worker when its parent dies, even by SIGKILL.

    On Linux it asks the kernel for SIGTERM when the parent dies (``prctl(PR_SET_PDEATHSIG, SIGTERM)``
    through ctypes); elsewhere, or if that fails, a daemon thread checks every 0.2 s whether ``os.getppid()``
    changed and ends the worker if so. A worker whose parent died before this ran ends at once. The default
    process pool of :func:`~flatstep.studies.batch.run_batch` uses it; give it to your own pool as
    ``ProcessPoolExecutor(initializer=die_with_parent, initargs=(os.getpid(),))``.

    Parameters
    ----------
    parent : int
        The pid of the process that runs the batch.

    Notes
    -----
    The kernel sends the signal when the *thread* that started the worker ends: the pool must be created and
    used by one thread that outlives it (as :func:`~flatstep.studies.batch.run_batch` does).
    """
    armed = False
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            armed = libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0) == 0
        except (OSError, AttributeError):
            armed = False
    ppid = os.getppid()
    if not pid_alive(parent) or (ppid == 1 and parent != 1):  # the parent died before the signal was asked for
        os._exit(1)
    if not armed:
        def watch() -> None:
            while os.getppid() == ppid:
                time.sleep(0.2)
            os._exit(1)

        threading.Thread(target=watch, name="flatstep-die-with-parent", daemon=True).start()
