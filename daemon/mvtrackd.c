/*
 * mvtrackd - multi-camera 3D people tracker daemon (docs/interfaces.md section 3). The engine's interface
 * is mvtd.h (engine.h maps its files); this is its command-line entry point.
 */
#include "mvtd.h"

static mvtd_t g_state; /* large (the tracker and its workspaces): static, not on the stack */

int main(int argc, char **argv)
{
    mvtd_t *d = &g_state;
    int rc = mvtd_configure(d, argc, argv);
    if (rc != MVTD_CONTINUE) {
        return rc;
    }
    rc = mvtd_open(d);
    if (rc != MVTD_CONTINUE) {
        return rc;
    }
    rc = mvtd_run(d);
    mvtd_finish(d);
    return rc;
}
