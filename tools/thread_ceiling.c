/* What a second thread gains on this machine, by kind of work, so that a
 * build's speedup over threads can be read against what the machine
 * allows (docs/performance.md, "What two threads can gain here").
 *
 *   cc -O2 -pthread tools/thread_ceiling.c -o /tmp/thread_ceiling
 *   /tmp/thread_ceiling KIND BYTES [ROUNDS]
 *
 * Each round times the work on one thread, then the same work on each of
 * two threads at once, and prints 2 x (one thread's time) / (two threads'
 * time): 2 where the threads do not slow each other, 1 where the second
 * thread gains nothing. KIND:
 *   0  arithmetic: BYTES steps of one chain of multiply-adds
 *   1  fresh pages: malloc BYTES, write a byte a cache line, free
 *   2  memory already written: a byte a line over BYTES, four times
 *   3  random reads: BYTES / 64 reads at random in 64 MB
 * Plain C: libc and pthreads only. */
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec * 1e-9;
}

typedef struct {
    int kind;
    size_t bytes;
    char *kept; /* this thread's memory, written before the timing */
    uint64_t out;
} job;

static void *work(void *p) {
    job *j = p;
    uint64_t acc = 0, x = 12345;
    switch (j->kind) {
    case 0:
        for (size_t i = 0; i < j->bytes; i++) {
            x = x * 6364136223846793005ULL + 1442695040888963407ULL;
            acc += x >> 60;
        }
        break;
    case 1: {
        char *m = malloc(j->bytes);
        if (!m) abort();
        for (size_t i = 0; i < j->bytes; i += 64) m[i] = (char)i;
        acc = m[j->bytes / 2];
        free(m);
    } break;
    case 2:
        for (int r = 0; r < 4; r++)
            for (size_t i = 0; i < j->bytes; i += 64) j->kept[i] = (char)(i + r);
        acc = j->kept[7];
        break;
    case 3: {
        const uint32_t *m = (const uint32_t *)j->kept;
        size_t n = (64u << 20) / 4;
        for (size_t i = 0; i < j->bytes / 64; i++) {
            x = x * 6364136223846793005ULL + 1;
            acc += m[(x >> 20) % n];
        }
    } break;
    }
    j->out = acc;
    return NULL;
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: thread_ceiling KIND BYTES [ROUNDS] (see the source's head)\n");
        return 2;
    }
    int kind = atoi(argv[1]);
    size_t bytes = strtoull(argv[2], NULL, 10);
    int rounds = argc > 3 ? atoi(argv[3]) : 5;
    if (kind < 0 || kind > 3 || bytes == 0 || rounds < 1) {
        fprintf(stderr, "thread_ceiling: KIND is 0 to 3, BYTES and ROUNDS positive\n");
        return 2;
    }
    size_t keep = bytes > (64u << 20) ? bytes : (64u << 20);
    char *kept[2];
    for (int i = 0; i < 2; i++) {
        kept[i] = malloc(keep);
        if (!kept[i]) abort();
        for (size_t b = 0; b < keep; b += 64) kept[i][b] = (char)b;
    }
    for (int r = 0; r < rounds; r++) {
        double t[3];
        for (int threads = 1; threads <= 2; threads++) {
            pthread_t h[2];
            job j[2];
            double start = now();
            for (int i = 0; i < threads; i++) {
                j[i] = (job){kind, bytes, kept[i], 0};
                pthread_create(&h[i], NULL, work, &j[i]);
            }
            for (int i = 0; i < threads; i++) pthread_join(h[i], NULL);
            t[threads] = now() - start;
        }
        printf("kind %d: one thread %.3f s, two %.3f s: speedup %.2f\n", kind, t[1], t[2],
               2 * t[1] / t[2]);
    }
    return 0;
}
