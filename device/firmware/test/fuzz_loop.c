/* A driver for fuzz_rx.c where libFuzzer is not available (gcc only): random mutations
 * (bit flips, byte changes, insertions, deletions, splices) of the seed files for a
 * bounded time, each input run through LLVMFuzzerTestOneInput under the sanitizers.
 * Usage: fuzz_loop SECONDS SEED_FILE...   (on a failure the input is saved as
 * fuzz_loop-crash, then the sanitizer's report or the abort ends the run). */
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define MAX_INPUT 9000
#define MAX_SEEDS 4096

static uint8_t *seeds[MAX_SEEDS];
static size_t seed_len[MAX_SEEDS];
static uint64_t rng = 88172645463325252ull;

static uint8_t buf[MAX_INPUT];
static size_t buf_len;

static void save_input(void)
{
    int fd = open("fuzz_loop-crash", O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
        ssize_t w = write(fd, buf, buf_len);
        (void)w;
        close(fd);
    }
}

static void on_fatal(int sig)
{
    save_input();
    signal(sig, SIG_DFL);
    raise(sig);
}

void __sanitizer_set_death_callback(void (*callback)(void));

static uint64_t next(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static size_t mutate(uint8_t *in, size_t n, size_t nseeds)
{
    int edits = 1 + (int)(next() % 8);
    for (int e = 0; e < edits; e++) {
        size_t at = n ? next() % n : 0;
        switch (next() % 5) {
        case 0:
            if (n)
                in[at] ^= (uint8_t)(1u << (next() % 8));
            break;
        case 1:
            if (n)
                in[at] = (uint8_t)next();
            break;
        case 2:
            if (n < MAX_INPUT) {
                memmove(in + at + 1, in + at, n - at);
                in[at] = (uint8_t)next();
                n++;
            }
            break;
        case 3:
            if (n > 2) {
                memmove(in + at, in + at + 1, n - at - 1);
                n--;
            }
            break;
        default: { /* splice in part of another seed */
            size_t s = next() % nseeds, from = seed_len[s] ? next() % seed_len[s] : 0;
            size_t len = seed_len[s] - from;
            if (len > MAX_INPUT - at)
                len = MAX_INPUT - at;
            memcpy(in + at, seeds[s] + from, len);
            if (at + len > n)
                n = at + len;
        }
        }
    }
    return n;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: fuzz_loop SECONDS SEED_FILE...\n");
        return 2;
    }
    double budget = atof(argv[1]);
    size_t nseeds = 0;
    for (int i = 2; i < argc && nseeds < MAX_SEEDS; i++) {
        FILE *f = fopen(argv[i], "rb");
        if (!f)
            continue;
        seeds[nseeds] = malloc(MAX_INPUT);
        seed_len[nseeds] = fread(seeds[nseeds], 1, MAX_INPUT, f);
        fclose(f);
        LLVMFuzzerTestOneInput(seeds[nseeds], seed_len[nseeds]);
        nseeds++;
    }
    if (!nseeds) {
        fprintf(stderr, "fuzz_loop: no readable seed files\n");
        return 2;
    }
    __sanitizer_set_death_callback(save_input);
    signal(SIGABRT, on_fatal);
    signal(SIGSEGV, on_fatal);
    unsigned long runs = 0;
    clock_t start = clock();
    while ((double)(clock() - start) / CLOCKS_PER_SEC < budget) {
        size_t s = next() % nseeds;
        memcpy(buf, seeds[s], seed_len[s]);
        buf_len = mutate(buf, seed_len[s], nseeds);
        LLVMFuzzerTestOneInput(buf, buf_len);
        runs++;
    }
    printf("fuzz_loop: %lu inputs in %.0f s, no failure\n", runs, budget);
    return 0;
}
