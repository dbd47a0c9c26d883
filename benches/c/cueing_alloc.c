/* LD_PRELOAD allocation counter for benches/c/cueing_host.c: counts the calls of every
 * allocating function of the C library between alloc_count_begin() and alloc_count_end()
 * (the host finds them with dlsym) and prints the count on stderr at exit. The allocations
 * themselves go to glibc's own (__libc_*). */
#include <stddef.h>
#include <stdio.h>
#include <errno.h>

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void *__libc_memalign(size_t, size_t);

static volatile int armed;
static volatile long allocations;

void alloc_count_begin(void) { allocations = 0; armed = 1; }
void alloc_count_end(void) { armed = 0; }

void *malloc(size_t n) { if (armed) allocations++; return __libc_malloc(n); }
void *calloc(size_t n, size_t m) { if (armed) allocations++; return __libc_calloc(n, m); }
void *realloc(void *p, size_t n) { if (armed) allocations++; return __libc_realloc(p, n); }
void *memalign(size_t a, size_t n) { if (armed) allocations++; return __libc_memalign(a, n); }
void *aligned_alloc(size_t a, size_t n) { if (armed) allocations++; return __libc_memalign(a, n); }
int posix_memalign(void **out, size_t a, size_t n) {
    if (armed) allocations++;
    void *p = __libc_memalign(a, n);
    if (!p) return ENOMEM;
    *out = p;
    return 0;
}

__attribute__((destructor)) static void report(void) { fprintf(stderr, "allocations %ld\n", allocations); }
