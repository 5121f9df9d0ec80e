/* subscribe_tracks.c - a program of your own that reads mvtrackd's tracks (README, "Consuming the
 * tracks"). Built by the tests (target subscribe_tracks) against LCM and the generated C types:
 *   cc subscribe_tracks.c -Ibuild/lcmtypes/c build/lcmtypes/libmvtrack_lcmtypes.a -llcm */
#include <stdio.h>

#include <lcm/lcm.h>

#include "mvtrack_tracks_t.h"

static void on_tracks(const lcm_recv_buf_t *rbuf, const char *channel, const mvtrack_tracks_t *msg, void *user)
{
    (void)rbuf, (void)channel, (void)user;
    for (int i = 0; i < msg->num_tracks; i++) {
        const mvtrack_track_t *t = &msg->tracks[i];
        if (t->status != MVTRACK_TRACK_T_TENTATIVE) {
            printf("%lld id %d at %.2f %.2f %.2f m\n", (long long)msg->utime, t->id, (double)t->position[0],
                   (double)t->position[1], (double)t->position[2]);
        }
    }
}

int main(int argc, char **argv)
{
    lcm_t *lcm = lcm_create(argc > 1 ? argv[1] : "udpm://239.255.76.67:7667?ttl=0");
    if (lcm == NULL) {
        return 1;
    }
    mvtrack_tracks_t_subscribe(lcm, "TRACKS", on_tracks, NULL);
    while (lcm_handle(lcm) == 0) {
    }
    lcm_destroy(lcm);
    return 0;
}
