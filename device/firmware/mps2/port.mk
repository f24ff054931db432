# The QEMU port (included by ../Makefile): MPS2-AN385, a Cortex-M3 that Debian's
# qemu-system-arm emulates. `make mps2` builds it; tests run it with its UART on a pty.
MPS2_DEFS := -DFW_MAX_CHANNELS=1 -DFW_STORE_WORDS=4096 -DFW_PHASES=0
MPS2_CFLAGS := -std=c11 -mcpu=cortex-m3 -mthumb -O2 -g -ffunction-sections -fdata-sections \
    -fno-common -Wall -Wextra -Wshadow $(MPS2_DEFS)
MPS2_LDFLAGS := -T mps2/mps2.ld -nostartfiles --specs=nano.specs --specs=nosys.specs \
    -Wl,--gc-sections
MPS2_SRC := $(CORE) cortexm/reset.c mps2/startup.c mps2/uart.c mps2/played_log.c mps2/main.c

$(BUILD)/mps2/frictex-fw-mps2.elf: $(MPS2_SRC) $(HDRS) $(wildcard cortexm/*.h mps2/*.h) mps2/mps2.ld
	@mkdir -p $(@D)
	$(ARM_CC) $(MPS2_CFLAGS) $(MPS2_SRC) $(MPS2_LDFLAGS) -o $@

mps2: $(BUILD)/mps2/frictex-fw-mps2.elf
