"""Running a closed loop: ``simulate`` and its result."""
