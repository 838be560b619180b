/* Processor features and the code chosen for them (tc_cpu.h). The CPUID and XGETBV instructions are read with GNU
 * inline assembly, which clang and GCC compile on every x86-64 target (Linux, Windows, macOS); any other compiler or
 * processor answers 0. */
#include "tc_cpu.h"

#include "tc_step_kernels_avx.h"

int tc_cpu_runs_avx(void) {
#if defined(__x86_64__) && (defined(__clang__) || defined(__GNUC__))
    unsigned a, b, c, d;
    __asm__("cpuid" : "=a"(a), "=b"(b), "=c"(c), "=d"(d) : "a"(1u), "c"(0u));
    const unsigned osxsave = 1u << 27, avx = 1u << 28;
    if ((c & osxsave) == 0 || (c & avx) == 0) return 0;
    unsigned lo, hi;
    __asm__("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0u)); /* XCR0: bit 1 the XMM state, bit 2 the YMM state */
    (void)a, (void)b, (void)d, (void)hi;
    return (lo & 6u) == 6u;
#else
    return 0;
#endif
}

const tc_step_kernels *tc_step_kernels_for_cpu(void) {
#if TC_STEP_KERNELS_AVX && !defined(TC_NO_AVX)
    if (tc_cpu_runs_avx()) return &tc_step_kernels_avx;
#endif
    return &tc_step_kernels_baseline;
}

int tc_step_kernels_avx_chosen(void) { return tc_step_kernels_for_cpu()->avx; }
