/* FNV-1a, 64 bits, of standard input, printed as 0x%016x: the tests' own
 * checksum, written apart from the workloads' code so that a checksum the
 * workloads print can be checked against an expected listing. */
#include <inttypes.h>
#include <stdio.h>

int main(void)
{
    uint64_t h = 0xcbf29ce484222325ull;
    int c;
    while ((c = getchar()) != EOF) {
        h ^= (uint64_t)(unsigned char)c;
        h *= 0x100000001b3ull;
    }
    printf("0x%016" PRIx64 "\n", h);
    return 0;
}
