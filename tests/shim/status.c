/* Prints its real and effective user ids and exits with status 3: built
 * statically (the loader never runs, so nothing is preloaded) and
 * dynamically (made set-user-ID by not_loaded.sh). */
#include <stdio.h>
#include <unistd.h>

int main(void)
{
    printf("uid %ld euid %ld\n", (long)getuid(), (long)geteuid());
    return 3;
}
