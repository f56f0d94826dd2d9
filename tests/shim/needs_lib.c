/* A program whose library the loader cannot find: built with no run path
 * beside a library of its own (NEEDS_LIB_LIBRARY), so the loader stops it
 * before main, with its own message and status 127 (not_loaded.sh). */
#ifdef NEEDS_LIB_LIBRARY
__attribute__((visibility("default"))) int needs_lib_status(void);
int needs_lib_status(void)
{
    return 3;
}
#else
int needs_lib_status(void);

int main(void)
{
    return needs_lib_status();
}
#endif
