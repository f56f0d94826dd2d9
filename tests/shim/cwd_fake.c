/* A library that must never be loaded: copied into the directory a test
 * runs emm from, under the names of the libraries emm's own depend on. On
 * load it leaves a file there, so the test sees that it was. */
#include <fcntl.h>
#include <unistd.h>

__attribute__((constructor)) static void loaded(void)
{
    int fd = open("loaded-from-the-current-directory", O_WRONLY | O_CREAT, 0644);
    if (fd >= 0)
        close(fd);
}
