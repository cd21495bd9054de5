"""Studies of many runs: scenarios, scenario files, batches, robustness, controller comparison."""
