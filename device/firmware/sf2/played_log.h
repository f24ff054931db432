/* The played-sample log: a record per played sample (its number, u32, and a u16 setpoint
 * per channel, little-endian), queued by the sample interrupt and written by the main
 * loop in batches through semihosting into BOARD_PLAYED_LOG in QEMU's working folder
 * (the launcher makes it a FIFO). One trap per batch: a UART would cost QEMU an I/O exit
 * per byte, which under -icount slowed it below 10 kHz of records. */
#ifndef PLAYED_LOG_H
#define PLAYED_LOG_H

#include <stdbool.h>
#include <stdint.h>

#include "../core/device.h"

void played_log_open(void);
/* From the sample interrupt: note what this tick played; false if the queue was full. */
bool played_log_note(const fw_output *o);
/* From the main loop: write what is queued if a batch is due at tick now (or always,
 * with force); true when nothing is left queued. */
bool played_log_flush(uint32_t now, bool force);

#endif
