/* fork + exec under the shim: the child execs the program given as argv[1]
 * (with LD_PRELOAD still set, so the shim loads again there) and the parent
 * waits and prints its exit status. A second child only forks and exits. */
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

int main(int argc, char **argv)
{
    if (argc < 2)
        return 2;
    double *a = malloc(8 * 100000);
    if (!a)
        return 1;
    for (int i = 0; i < 100000; i++)
        a[i] = i;
    fflush(stdout);
    pid_t pid = fork();
    if (pid < 0)
        return 1;
    if (pid == 0) {
        execv(argv[1], argv + 1);
        _exit(127);
    }
    int status;
    if (waitpid(pid, &status, 0) != pid)
        return 1;
    printf("exec child: %d\n", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    fflush(stdout);
    pid = fork();
    if (pid == 0) {
        double s = 0;
        for (int i = 0; i < 100000; i++)
            s += a[i];
        _exit(s == 4999950000.0 ? 7 : 8);
    }
    if (waitpid(pid, &status, 0) != pid)
        return 1;
    printf("fork child: %d\n", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    free(a);
    return 0;
}
