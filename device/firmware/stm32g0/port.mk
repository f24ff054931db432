# The Cortex-M0+ port (included by ../Makefile): arm-none-eabi-gcc -Os, newlib-nano for
# memcpy/memset/strlen. `make stm32g0` builds and prints flash and RAM use.
ARM_CC := $(ARM_PREFIX)gcc
ARM_SIZE := $(ARM_PREFIX)size
ARM_OBJCOPY := $(ARM_PREFIX)objcopy
ARM_DEFS := -DFW_MAX_CHANNELS=2 -DFW_STORE_WORDS=800 -DFW_PHASES=0
ARM_CFLAGS := -std=c11 -mcpu=cortex-m0plus -mthumb -Os -g -ffunction-sections -fdata-sections \
    -fno-common -Wall -Wextra -Wshadow $(ARM_DEFS) -fstack-usage
ARM_LDFLAGS := -T stm32g0/stm32g0.ld -nostartfiles --specs=nano.specs --specs=nosys.specs \
    -Wl,--gc-sections -Wl,-Map=$(BUILD)/stm32g0/frictex-fw.map
ARM_SRC := $(CORE) cortexm/reset.c stm32g0/startup.c stm32g0/clock.c stm32g0/uart.c stm32g0/sample_clock.c \
    stm32g0/main.c

$(BUILD)/stm32g0/frictex-fw.elf: $(ARM_SRC) $(HDRS) $(wildcard cortexm/*.h stm32g0/*.h) stm32g0/stm32g0.ld
	@mkdir -p $(@D)
	$(ARM_CC) $(ARM_CFLAGS) $(ARM_SRC) $(ARM_LDFLAGS) -o $@

$(BUILD)/stm32g0/frictex-fw.bin: $(BUILD)/stm32g0/frictex-fw.elf
	$(ARM_OBJCOPY) -O binary $< $@

stm32g0: $(BUILD)/stm32g0/frictex-fw.bin
	$(ARM_SIZE) -A $(BUILD)/stm32g0/frictex-fw.elf | grep -E '^(section|\.isr_vector|\.text|\.data|\.bss|\.stack) '
	@$(ARM_SIZE) $(BUILD)/stm32g0/frictex-fw.elf | awk 'NR==2 { \
	    printf "flash %d of 32768 bytes, RAM %d of 8192 bytes (static; stack reserved in .stack)\n", \
	    $$1 + $$2, $$2 + $$3 }'
