/*
 * extlib.c - loading a shared library on first use (extlib.h).
 *
 * RTLD_LAZY, as the dynamic linker binds a library a program links:
 * binding every symbol of GDAL and its dependencies at once (RTLD_NOW)
 * costs some 15 ms of CPU more, and each function dfle calls is looked
 * up here anyway, so a library that lacks one fails now, with dlerror's
 * words, not in the middle of writing a file.  RTLD_LOCAL: the
 * library's symbols stay out of the global scope, as they would be out
 * of the process had it not been loaded.  It is never closed: GDAL registers exit
 * handlers and keeps drivers, and a second load would cost as much as
 * the first.  One attempt per process: a library does not appear while
 * a run goes on, and every later call gets the first call's reason.
 */
#include "base/extlib.h"

#include <dlfcn.h>
#include <stdio.h>
#include <string.h>

/* dlsym returns an object pointer that goes into a function pointer;
 * POSIX guarantees the two have the same size and representation. */
_Static_assert(sizeof(void *) == sizeof(void (*)(void)),
               "dlsym's addresses must fit a function pointer");

static void set_why(dfle_extlib *lib, const char *fallback)
{
    const char *e = dlerror();
    snprintf(lib->why, sizeof lib->why, "%s", e != NULL ? e : fallback);
}

static void open_lib(dfle_extlib *lib)
{
    void *h, *addr;

    lib->status = DFLE_EEXTERNAL;
    dlerror(); /* clear any earlier message */
    if ((h = dlopen(lib->soname, RTLD_LAZY | RTLD_LOCAL)) == NULL) {
        set_why(lib, "cannot open the library");
        return;
    }
    for (size_t k = 0; k < lib->n; k++) {
        dlerror();
        if ((addr = dlsym(h, lib->syms[k].name)) == NULL) {
            set_why(lib, "a function is missing");
            return; /* h stays open: dlclose could run the library's exit code */
        }
        memcpy((char *)lib->table + lib->syms[k].offset, &addr, sizeof addr);
    }
    lib->why[0] = '\0';
    lib->status = DFLE_OK;
    if (lib->loaded != NULL)
        lib->loaded();
}

int dfle_extlib_load(dfle_extlib *lib, const char *who, dfle_error *err)
{
    pthread_mutex_lock(&lib->lock);
    if (!lib->tried) {
        open_lib(lib);
        lib->tried = 1;
    }
    pthread_mutex_unlock(&lib->lock);
    if (lib->status == DFLE_OK)
        return DFLE_OK;
    if (lib->package[0] != '\0')
        return dfle_error_set(err, lib->status, "%s: %s could not be loaded: %s; install %s, or "
                              "rebuild dfle against the %s that is installed (this build uses %s)",
                              who, lib->what, lib->why, lib->package, lib->what, lib->soname);
    return dfle_error_set(err, lib->status, "%s: %s could not be loaded: %s; install the package "
                          "that provides %s, or rebuild dfle against the %s that is installed",
                          who, lib->what, lib->why, lib->soname, lib->what);
}
