# Cross build of the C core for an ARM Cortex-M4F (float), not part of `make test`: `make embedded`
# skips with a message when arm-none-eabi-gcc (or QEMU, for the executed-instruction count) is absent.
.PHONY: embedded bench

embedded:
	sh embedded/build.sh

# Every benchmark of docs/benchmarks.md, side by side, with medians and ratios.
bench: venv
	$(BIN)/python -m pip install -q -e '.[bench]'
	$(BIN)/flatstep bench
