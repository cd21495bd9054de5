# Cross builds of the C core for an ARM Cortex-M4F (float), not part of `make test`: `make embedded` runs the four
# scripts of embedded/ (the controller step, the trajectory evaluator, the time-optimal planner, the field-weakening
# planner); each skips with a message when arm-none-eabi-gcc (or QEMU, for the executed-instruction count) is absent.
# The field-weakening planner's count takes minutes (a trace of about 70 million instructions).
.PHONY: embedded bench

embedded:
	sh embedded/build.sh
	sh embedded/traj_build.sh
	sh embedded/time_optimal_build.sh
	sh embedded/time_optimal_dq_build.sh

# Every benchmark of docs/benchmarks.md, side by side, with medians and ratios.
bench: venv
	$(BIN)/python -m pip install -q -e '.[bench]'
	$(BIN)/flatstep bench
