#!/usr/bin/env bash
# Whether two threads can run at twice the speed of one on this machine: times three loops (an
# integer multiply-xor chain, eight independent AVX2 FMA chains, a 4 MB read-modify-write stream)
# once alone and then two copies at once. Copies that keep their solo time mean two independent
# cores for that work; copies that slow to 1.6-2x their solo time mean shared execution units (SMT
# siblings) or shared memory bandwidth, which caps any program's 1 -> 2 thread gain there.
# Read beside the "1 -> 2 threads" figures of docs/results.md (issues #16, #17).
#
# usage: scripts/cores.sh [ROUNDS]    (needs gcc and an x86-64 CPU with AVX2 + FMA; ~5 s a round)
set -euo pipefail
rounds="${1:-2}"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cat >"$dir/cores.c" <<'C'
#include <immintrin.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + t.tv_nsec * 1e-9; }
int main(int argc, char** argv) {
    const int kind = atoi(argv[1]);
    const long n = atol(argv[2]);
    volatile unsigned long sink = 0;
    const double t0 = now();
    if (kind == 0) {
        unsigned long a = 1, b = 2, c = 3, d = 4;
        for (long i = 0; i < n; i++) { a = a * 3 + b; b ^= a >> 3; c = c * 5 + d; d ^= c >> 7; }
        sink = a + b + c + d;
    } else if (kind == 1) {
        __m256 x[8];
        const __m256 m = _mm256_set1_ps(0.9999f), k = _mm256_set1_ps(0.0001f);
        for (int j = 0; j < 8; j++) x[j] = _mm256_set1_ps(1.0f + j);
        for (long i = 0; i < n; i++)
            for (int j = 0; j < 8; j++) x[j] = _mm256_fmadd_ps(x[j], m, k);
        float o[8];
        __m256 s = x[0];
        for (int j = 1; j < 8; j++) s = _mm256_add_ps(s, x[j]);
        _mm256_storeu_ps(o, s);
        sink = (unsigned long)o[0];
    } else {
        const size_t size = (size_t)1 << 20;
        unsigned* buf = aligned_alloc(64, size * sizeof(unsigned));
        for (size_t i = 0; i < size; i++) buf[i] = (unsigned)i;
        for (long r = 0; r < n; r++) {
            __m256i acc = _mm256_setzero_si256();
            for (size_t i = 0; i < size; i += 8) {
                const __m256i v = _mm256_load_si256((const __m256i*)(buf + i));
                acc = _mm256_add_epi32(acc, v);
                _mm256_store_si256((__m256i*)(buf + i), _mm256_max_epu32(v, acc));
            }
            sink += (unsigned)_mm256_extract_epi32(acc, 0);
        }
        free(buf);
    }
    printf("%.3f\n", now() - t0);
    return (int)(sink & 0);
}
C
gcc -O2 -mavx2 -mfma "$dir/cores.c" -o "$dir/cores"
echo "$(nproc) CPUs; $(uptime | sed 's/.*load/load/')"
for round in $(seq "$rounds"); do
  for spec in "integer 0 400000000" "avx2-fma 1 200000000" "stream-4MB 2 5000"; do
    set -- $spec
    alone=$("$dir/cores" "$2" "$3")
    both=$( ("$dir/cores" "$2" "$3" & "$dir/cores" "$2" "$3"; wait) | tr '\n' ' ')
    echo "round $round  $1: alone ${alone} s, two at once ${both}s"
  done
done
