/* Command line of the host port: the flags of `frictex sim-device` (but --tcp), plus
 * --rx-log. */
#ifndef HOST_CLI_H
#define HOST_CLI_H

#include "params.h"

typedef struct {
    host_params params;
    const char *played_log, *plate_log, *rx_log;
    long parent_pid; /* 0: none */
    bool once;       /* exit once a host's Stop has played out */
} host_cli;

/* 0: parsed; 1: --help printed; 2: bad input (the error is printed on stderr). */
int host_cli_parse(int argc, char **argv, host_cli *out);

#endif
