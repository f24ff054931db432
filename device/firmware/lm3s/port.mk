# The QEMU port (included by ../Makefile): LM3S6965EVB, a Cortex-M3 that Debian's
# qemu-system-arm emulates. `make lm3s` builds it; tests run it with its UART on a pty.
LM3S_DEFS := -DFW_MAX_CHANNELS=1 -DFW_STORE_WORDS=4096 -DFW_PHASES=0
LM3S_CFLAGS := -std=c11 -mcpu=cortex-m3 -mthumb -O2 -g -ffunction-sections -fdata-sections \
    -fno-common -Wall -Wextra -Wshadow $(LM3S_DEFS)
LM3S_LDFLAGS := -T lm3s/lm3s.ld -nostartfiles --specs=nano.specs --specs=nosys.specs \
    -Wl,--gc-sections
LM3S_SRC := $(CORE) cortexm/reset.c lm3s/startup.c lm3s/uart.c lm3s/played_log.c lm3s/main.c

$(BUILD)/lm3s/frictex-fw-lm3s.elf: $(LM3S_SRC) $(HDRS) $(wildcard cortexm/*.h lm3s/*.h) lm3s/lm3s.ld
	@mkdir -p $(@D)
	$(ARM_CC) $(LM3S_CFLAGS) $(LM3S_SRC) $(LM3S_LDFLAGS) -o $@

lm3s: $(BUILD)/lm3s/frictex-fw-lm3s.elf
