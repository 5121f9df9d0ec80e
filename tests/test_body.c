/* Black-box scenes for the tracker's model of a person: rates over seeds, no internal
 * fields read. The blobs are drawn here from a body (a 0.4 m wide column under the head) projected
 * through the room's cameras, lens included. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "mvt_body.h"
#include "mvt_tracker.h"
#include "test_support.h"

static mvt_tracker_t g_tracker; /* large: static */
static mvt_frame_t g_frame;
static mvt_output_t g_out;

/* The room's body-model tracker on its first n_cams cameras; the box lo..hi declared as a static
 * occluder when lo is given. */
static void init_body_with(mvt_camera_t cams[5], int n_cams, const double *lo, const double *hi)
{
    assert_int_equal(test_room_cameras(cams, 1), 0);
    mvt_tracker_config_t cfg;
    mvt_tracker_config_default(&cfg);
    cfg.volume.min[0] = 0; cfg.volume.min[1] = 0; cfg.volume.min[2] = 0;
    cfg.volume.max[0] = 6; cfg.volume.max[1] = 5; cfg.volume.max[2] = 2.5f;
    if (lo != NULL) {
        cfg.volume.num_occluders = 1;
        for (int j = 0; j < 3; j++) {
            cfg.volume.occluder_min[0][j] = (mvt_real)lo[j];
            cfg.volume.occluder_max[0][j] = (mvt_real)hi[j];
        }
    }
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, n_cams), MVT_OK);
}

static void init_body(mvt_camera_t cams[5], int n_cams)
{
    init_body_with(cams, n_cams, NULL, NULL);
}

/* The blob of a body with head x in camera cam: top point (noisy) and the box of the body's column,
 * cut by the picture. 0 when the head is not in the picture. */
static int body_blob(const mvt_camera_t *cam, const double x[3], double top_z, test_rng_t *rng, mvt_detection_t *det)
{
    double box[4] = {1e9, 1e9, -1e9, -1e9};
    for (int i = 0; i < 8; i++) {
        const double a = i * 0.785398;
        for (int h = 0; h < 2; h++) {
            const mvt_real p[3] = {(mvt_real)(x[0] + 0.2 * cos(a)), (mvt_real)(x[1] + 0.2 * sin(a)), (mvt_real)(h ? top_z : 0.0)};
            mvt_real uv[2];
            if (mvt_cam_project(cam, p, uv, NULL) != MVT_OK) return 0;
            box[0] = fmin(box[0], (double)uv[0]); box[1] = fmin(box[1], (double)uv[1]);
            box[2] = fmax(box[2], (double)uv[0]); box[3] = fmax(box[3], (double)uv[1]);
        }
    }
    const mvt_real head[3] = {(mvt_real)x[0], (mvt_real)x[1], (mvt_real)top_z};
    mvt_real uv[2];
    if (mvt_cam_project(cam, head, uv, NULL) != MVT_OK || uv[0] < 0 || uv[1] < 0 || uv[0] > 767 || uv[1] > 575) return 0;
    memset(det, 0, sizeof(*det));
    det->u = uv[0] + (mvt_real)(2.0 * test_normal(rng));
    det->v = uv[1] + (mvt_real)(2.0 * test_normal(rng));
    det->sigma_px = 2.0f;
    det->score = 1.0f;
    det->hue = det->saturation = -1.0f;
    det->box[0] = (mvt_real)fmax(box[0], 0.0);
    det->box[1] = (mvt_real)fmax(box[1], 0.0);
    det->box[2] = (mvt_real)fmin(box[2], 767.0);
    det->box[3] = (mvt_real)fmin(box[3], 575.0);
    return 1;
}

static void blank(int n_cams, int64_t t)
{
    memset(&g_frame, 0, sizeof(g_frame));
    g_frame.utime_us = t;
    for (int k = 0; k < n_cams; k++) {
        g_frame.views[k].observed = 1;
        g_frame.views[k].utime_us = t;
    }
}

static void add(int k, const mvt_detection_t *d)
{
    mvt_view_t *v = &g_frame.views[k];
    if (v->num_detections < MVT_MAX_DETECTIONS) v->det[v->num_detections++] = *d;
}

static int confirmed(void)
{
    int n = 0;
    for (int i = 0; i < g_out.num_tracks; i++) {
        n += g_out.tracks[i].status == MVT_TRACK_CONFIRMED || g_out.tracks[i].status == MVT_TRACK_COASTING;
    }
    return n;
}

/* One camera alone: a person walking is born from that view (head ray, height prior, feet) within
 * 5 frames, rarely changes identity, and is placed in 3D by head and feet. 20 seeds, 200 frames. */
static void test_body_one_camera_person_tracked_in_3d(void **state)
{
    (void)state;
    int switches = 0, late = 0, frames = 0;
    double se = 0;
    for (int seed = 1; seed <= 20; seed++) {
        mvt_camera_t cams[5];
        init_body(cams, 1);
        test_rng_t rng = {(unsigned long long)seed * 7919ULL};
        const double h = 1.6 + 0.2 * test_uniform(&rng);
        int32_t id = -1;
        int first = -1;
        for (int f = 0; f < 200; f++) {
            const double ts = f * 0.04;
            const double x[3] = {2.0 + 0.4 * ts * cos(seed), 2.5 + 0.4 * ts * sin(seed), h};
            blank(1, 1000000 + f * 40000);
            mvt_detection_t d;
            if (body_blob(&cams[0], x, h, &rng, &d) && test_uniform(&rng) < 0.9) add(0, &d);
            assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
            for (int i = 0; i < g_out.num_tracks; i++) {
                const mvt_track_out_t *o = &g_out.tracks[i];
                if (o->status == MVT_TRACK_TENTATIVE) continue;
                if (first < 0) first = f;
                if (id >= 0 && o->id != id) switches++;
                id = o->id;
                if (f >= 25) {
                    for (int a = 0; a < 3; a++) se += ((double)o->pos_m[a] - x[a]) * ((double)o->pos_m[a] - x[a]);
                    frames++;
                }
            }
        }
        late += first < 0 || first > 5;
    }
    const double rms = sqrt(se / (frames > 0 ? frames : 1));
    print_message("one camera, 20 seeds: %d identity changes, %d late births, 3D RMS %.3f m over %d frames\n", switches,
                  late, rms, frames);
    /* measured: 2 identity changes, none late, 0.090 m over 3,265 frames (some walks leave the
     * picture) */
    assert_true(switches <= 2);
    assert_int_equal(late, 0);
    assert_true(frames > 20 * 150);
    assert_true(rms < 0.15);
}

/* Five cameras, two people, each view's blob of a person split: the head's blob and, half of the
 * time, a torso fragment (its top 0.7 m under the head, on the body). The fragments never become
 * people. 10 seeds, 150 frames. */
static void test_body_fragments_support_and_never_become_people(void **state)
{
    (void)state;
    int wrong = 0, low = 0, frames = 0;
    for (int seed = 1; seed <= 10; seed++) {
        mvt_camera_t cams[5];
        init_body(cams, 5);
        test_rng_t rng = {(unsigned long long)seed * 104729ULL};
        for (int f = 0; f < 150; f++) {
            const double ts = f * 0.04;
            const double p[2][3] = {{1.5 + 0.3 * ts, 1.5, 1.75}, {4.5 - 0.2 * ts, 3.5, 1.62}};
            blank(5, 1000000 + f * 40000);
            for (int k = 0; k < 5; k++) {
                for (int i = 0; i < 2; i++) {
                    mvt_detection_t d, frag;
                    if (body_blob(&cams[k], p[i], p[i][2], &rng, &d) && test_uniform(&rng) < 0.9) add(k, &d);
                    if (test_uniform(&rng) < 0.5 && body_blob(&cams[k], p[i], p[i][2] - 0.7, &rng, &frag)) add(k, &frag);
                }
            }
            assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
            if (f < 10) continue;
            frames++;
            wrong += confirmed() != 2;
            for (int i = 0; i < g_out.num_tracks; i++) {
                low += g_out.tracks[i].status != MVT_TRACK_TENTATIVE && g_out.tracks[i].pos_m[2] < 1.3f;
            }
        }
    }
    print_message("fragments, 10 seeds: %d of %d frames without exactly two people, %d low tracks\n", wrong, frames, low);
    assert_int_equal(low, 0);
    assert_true(wrong * 100 <= frames);
}

/* An empty room whose five cameras each see one false blob a frame, anywhere: no confirmed track
 * in 99 % of frames. 5 seeds, 250 frames. */
static void test_body_clutter_alone_confirms_nobody(void **state)
{
    (void)state;
    int with = 0, frames = 0;
    for (int seed = 1; seed <= 5; seed++) {
        mvt_camera_t cams[5];
        init_body(cams, 5);
        test_rng_t rng = {(unsigned long long)seed * 31337ULL};
        for (int f = 0; f < 250; f++) {
            blank(5, 1000000 + f * 40000);
            for (int k = 0; k < 5; k++) {
                mvt_detection_t d;
                memset(&d, 0, sizeof(d));
                d.u = (mvt_real)(767.0 * test_uniform(&rng));
                d.v = (mvt_real)(575.0 * test_uniform(&rng));
                d.box[0] = d.u - 20; d.box[1] = d.v; d.box[2] = d.u + 20; d.box[3] = d.v + 60;
                d.hue = d.saturation = -1;
                add(k, &d);
            }
            assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
            frames++;
            with += confirmed() > 0;
        }
    }
    print_message("clutter, 5 seeds: %d of %d frames with a confirmed track\n", with, frames);
    assert_true(with * 100 <= frames);
}

/* The desk of the test below: a sideboard 0.9 m high between camera 0 and the people behind it. */
static const double DESK_MIN[3] = {1.0, 2.0, 0.0}, DESK_MAX[3] = {5.0, 2.6, 0.9};

/* 1 when the segment from a to b passes through the desk (sampled every centimetre of its length). */
static int through_desk(const double a[3], const double b[3])
{
    const double len = sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]));
    const int n = (int)(len / 0.01) + 1;
    for (int i = 1; i < n; i++) {
        const double s = (double)i / n;
        int in = 1;
        for (int j = 0; j < 3; j++) {
            const double p = a[j] + s * (b[j] - a[j]);
            in &= p >= DESK_MIN[j] && p <= DESK_MAX[j];
        }
        if (in) return 1;
    }
    return 0;
}

/* body_blob's blob with the parts of the body's column that the desk hides from cam left out: its
 * box's bottom is the desk's edge where the desk hides the legs. */
static int body_blob_behind_desk(const mvt_camera_t *cam, const double x[3], test_rng_t *rng, mvt_detection_t *det)
{
    if (!body_blob(cam, x, x[2], rng, det)) return 0;
    const double c[3] = {(double)cam->centre[0], (double)cam->centre[1], (double)cam->centre[2]};
    double bottom = -1e9;
    for (int i = 0; i < 8; i++) {
        const double a = i * 0.785398;
        for (double z = 0.0; z <= x[2]; z += 0.02) {
            const double p[3] = {x[0] + 0.2 * cos(a), x[1] + 0.2 * sin(a), z};
            mvt_real uv[2];
            const mvt_real pr[3] = {(mvt_real)p[0], (mvt_real)p[1], (mvt_real)p[2]};
            if (!through_desk(c, p) && mvt_cam_project(cam, pr, uv, NULL) == MVT_OK) bottom = fmax(bottom, (double)uv[1]);
        }
    }
    det->box[3] = (mvt_real)fmin(bottom, 575.0);
    return 1;
}

/* One camera (the room's corner camera 0) and a person walking behind a sideboard 0.9 m high that
 * hides their legs: the blob's bottom is the sideboard's edge, not the feet, which would put the
 * person about a metre too far along the camera's ray. Declared in the rig (mvt_volume_t's
 * occluders), the sideboard makes that bottom no foot point, and the head's ray with the height
 * prior places the person; undeclared, the edge taken for feet drags them off (the test can
 * fail). 10 seeds, 200 frames, heights 1.6-1.8 m. */
static double desk_rms(int declared)
{
    double se = 0;
    int frames = 0;
    for (int seed = 1; seed <= 10; seed++) {
        mvt_camera_t cams[5];
        init_body_with(cams, 1, declared ? DESK_MIN : NULL, DESK_MAX);
        test_rng_t rng = {(unsigned long long)seed * 6151ULL};
        const double h = 1.6 + 0.2 * test_uniform(&rng);
        for (int f = 0; f < 200; f++) {
            const double x[3] = {1.5 + 3.0 * f / 200.0, 3.0, h};
            blank(1, 1000000 + f * 40000);
            mvt_detection_t d;
            if (body_blob_behind_desk(&cams[0], x, &rng, &d)) add(0, &d);
            assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
            for (int i = 0; i < g_out.num_tracks && f >= 25; i++) {
                const mvt_track_out_t *o = &g_out.tracks[i];
                if (o->status == MVT_TRACK_TENTATIVE) continue;
                for (int a = 0; a < 3; a++) se += ((double)o->pos_m[a] - x[a]) * ((double)o->pos_m[a] - x[a]);
                frames++;
            }
        }
    }
    assert_true(frames > 10 * 150);
    return sqrt(se / frames);
}

static void test_body_feet_behind_declared_furniture_not_used(void **state)
{
    (void)state;
    const double undeclared = desk_rms(0), declared = desk_rms(1);
    print_message("behind a sideboard, one camera: 3D RMS %.3f m undeclared, %.3f m declared\n", undeclared, declared);
    /* measured: 0.991 m undeclared, 0.311 m declared (the height prior 1.70 m against people of
     * 1.6-1.8 m, seen 1 m below the camera and 3 m away) */
    assert_true(declared < 0.4 && declared < 0.5 * undeclared);
}

/* The body model's parameters outside their physical ranges are refused. */
static void test_body_config_out_of_range_rejected(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    assert_int_equal(test_room_cameras(cams, 0), 0);
    mvt_tracker_config_t cfg;
    mvt_tracker_config_default(&cfg);
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_OK);
    mvt_tracker_config_t bad = cfg;
    bad.body.head_height_m = 0.5f;
    assert_int_equal(mvt_tracker_init(&g_tracker, &bad, cams, 5), MVT_ERR_INVALID);
    bad = cfg;
    bad.population.exist_delete = 0.6f;
    assert_int_equal(mvt_tracker_init(&g_tracker, &bad, cams, 5), MVT_ERR_INVALID);
    bad = cfg;
    bad.population.birth_per_s = 0.0f;
    assert_int_equal(mvt_tracker_init(&g_tracker, &bad, cams, 5), MVT_ERR_INVALID);
    bad = cfg;
    bad.volume.num_occluders = 1;
    bad.volume.occluder_min[0][0] = bad.volume.occluder_max[0][0] = 1.0f; /* an empty box */
    assert_int_equal(mvt_tracker_init(&g_tracker, &bad, cams, 5), MVT_ERR_INVALID);
    bad.volume.num_occluders = MVT_MAX_OCCLUDERS + 1;
    assert_int_equal(mvt_tracker_init(&g_tracker, &bad, cams, 5), MVT_ERR_INVALID);
}

/* Every point mvt_body_fragment_of counts as a fragment of a body lies in the box
 * mvt_body_fragment_bounds gives for it (the tracker tests the box first): random axes in every
 * direction, points on a grid around them at sub-pixel spacing. */
static void test_body_fragments_inside_their_bounds(void **state)
{
    (void)state;
    test_rng_t rng = {424242ULL};
    long inside = 0;
    for (int n = 0; n < 2000; n++) {
        mvt_real axis[MVT_BODY_AXIS_N];
        for (int i = 0; i < 4; i++) {
            axis[i] = (mvt_real)(2000.0 * test_uniform(&rng) - 500.0);
        }
        axis[4] = (mvt_real)(1.0 + 80.0 * test_uniform(&rng));
        axis[5] = test_uniform(&rng) < 0.2 ? MVT_R(0.0) : (mvt_real)(60.0 * test_uniform(&rng));
        mvt_real box[4];
        mvt_body_fragment_bounds(axis, box);
        const double lo_u = box[0] - 20.0, hi_u = box[2] + 20.0, lo_v = box[1] - 20.0, hi_v = box[3] + 20.0;
        for (int j = 0; j < 400; j++) {
            const mvt_real uv[2] = {(mvt_real)(lo_u + (hi_u - lo_u) * test_uniform(&rng)),
                                    (mvt_real)(lo_v + (hi_v - lo_v) * test_uniform(&rng))};
            if (mvt_body_fragment_of(axis, uv)) {
                inside++;
                assert_true(uv[0] >= box[0] && uv[0] <= box[2] && uv[1] >= box[1] && uv[1] <= box[3]);
            }
        }
    }
    assert_true(inside > 1000); /* the points reach the bodies */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_body_one_camera_person_tracked_in_3d),
        cmocka_unit_test(test_body_fragments_support_and_never_become_people),
        cmocka_unit_test(test_body_clutter_alone_confirms_nobody),
        cmocka_unit_test(test_body_feet_behind_declared_furniture_not_used),
        cmocka_unit_test(test_body_config_out_of_range_rejected),
        cmocka_unit_test(test_body_fragments_inside_their_bounds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
