# The QEMU port (included by ../Makefile): Emcraft's SmartFusion2 SOM, a Cortex-M3 that Debian's
# qemu-system-arm emulates. `make sf2` builds it; tests run it with its UART on a pty.
SF2_DEFS := -DFW_MAX_CHANNELS=1 -DFW_STORE_WORDS=4096 -DFW_PHASES=0
SF2_CFLAGS := -std=c11 -mcpu=cortex-m3 -mthumb -O2 -g -ffunction-sections -fdata-sections \
    -fno-common -Wall -Wextra -Wshadow $(SF2_DEFS)
SF2_LDFLAGS := -T sf2/sf2.ld -nostartfiles --specs=nano.specs --specs=nosys.specs \
    -Wl,--gc-sections
SF2_SRC := $(CORE) cortexm/reset.c sf2/startup.c sf2/uart.c sf2/played_log.c sf2/main.c

$(BUILD)/sf2/frictex-fw-sf2.elf: $(SF2_SRC) $(HDRS) $(wildcard cortexm/*.h sf2/*.h) sf2/sf2.ld
	@mkdir -p $(@D)
	$(ARM_CC) $(SF2_CFLAGS) $(SF2_SRC) $(SF2_LDFLAGS) -o $@

sf2: $(BUILD)/sf2/frictex-fw-sf2.elf
