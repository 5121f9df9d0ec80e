/* The daemon's wire check of camera_frame_t messages (mvtd_frame_wire_check) against lcm-gen's
 * encoder: every valid message passes and decodes; every truncation, negative or oversized count,
 * empty or unterminated camera name fails before lcm-gen's decoder could allocate from it. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "mvtd.h"
#include "mvtrack_camera_frame_t.h"

static uint8_t g_buf[1 << 16];

static int encode_random(unsigned seed, int *len)
{
    srand(seed);
    static mvtrack_detection_t dets[40];
    static int32_t runs[100];
    static uint8_t hue[64], sat[64];
    static char name[40];
    const int nl = rand() % 30;
    for (int i = 0; i < nl; i++) name[i] = (char)('a' + rand() % 26);
    name[nl] = '\0';
    mvtrack_camera_frame_t m;
    memset(&m, 0, sizeof(m));
    m.utime = rand();
    m.frame = rand();
    m.camera = name;
    m.width = 768;
    m.height = 576;
    m.num_detections = (int16_t)(rand() % 40);
    m.detections = dets;
    for (int i = 0; i < m.num_detections; i++) dets[i].u = (float)rand();
    m.num_runs = rand() % 100;
    m.runs = runs;
    m.num_hs = rand() % 2 ? 64 : 0;
    m.hue = hue;
    m.saturation = sat;
    *len = mvtrack_camera_frame_t_encode(g_buf, 0, sizeof(g_buf), &m);
    return m.num_detections;
}

static void test_wire_check_valid_messages_pass_and_decode(void **state)
{
    (void)state;
    for (unsigned s = 1; s <= 300; s++) {
        int len;
        const int nd = encode_random(s, &len);
        assert_true(len > 0);
        assert_int_equal(mvtd_frame_wire_check(g_buf, (uint32_t)len), 0);
        mvtrack_camera_frame_t m;
        assert_int_equal(mvtrack_camera_frame_t_decode(g_buf, 0, len, &m), len);
        assert_int_equal(m.num_detections, nd);
        mvtrack_camera_frame_t_decode_cleanup(&m);
    }
}

static void test_wire_check_every_truncation_fails(void **state)
{
    (void)state;
    for (unsigned s = 1; s <= 30; s++) {
        int len;
        encode_random(s, &len);
        for (int cut = 0; cut < len; cut++) {
            assert_int_not_equal(mvtd_frame_wire_check(g_buf, (uint32_t)cut), 0);
        }
    }
}

/* offset of the int16 num_detections: hash, utime, frame, then the name (int32 length + bytes) */
static size_t name_len_at(void) { return 24; }

static void put_be(uint8_t *p, int bytes, int64_t v)
{
    for (int i = bytes - 1; i >= 0; i--, v >>= 8) p[i] = (uint8_t)(v & 0xff);
}

static void test_wire_check_hostile_counts_and_names_fail(void **state)
{
    (void)state;
    int len;
    encode_random(7, &len);
    static uint8_t orig[sizeof(g_buf)];
    memcpy(orig, g_buf, (size_t)len);
    const uint32_t nl = ((uint32_t)g_buf[24] << 24) | ((uint32_t)g_buf[25] << 16) | ((uint32_t)g_buf[26] << 8) | g_buf[27];
    const size_t ndet_at = name_len_at() + 4 + nl + 4;
    /* negative and huge detection counts */
    const int64_t bad_counts[] = {-1, -32768, 32767};
    for (int i = 0; i < 3; i++) {
        memcpy(g_buf, orig, (size_t)len);
        put_be(g_buf + ndet_at, 2, bad_counts[i]);
        assert_int_not_equal(mvtd_frame_wire_check(g_buf, (uint32_t)len), 0);
    }
    /* name of length 0, length past the end, last byte not NUL */
    memcpy(g_buf, orig, (size_t)len);
    put_be(g_buf + 24, 4, 0);
    assert_int_not_equal(mvtd_frame_wire_check(g_buf, (uint32_t)len), 0);
    put_be(g_buf + 24, 4, 0x7fffffff);
    assert_int_not_equal(mvtd_frame_wire_check(g_buf, (uint32_t)len), 0);
    put_be(g_buf + 24, 4, -5);
    assert_int_not_equal(mvtd_frame_wire_check(g_buf, (uint32_t)len), 0);
    memcpy(g_buf, orig, (size_t)len);
    g_buf[28 + nl - 1] = 'x';
    assert_int_not_equal(mvtd_frame_wire_check(g_buf, (uint32_t)len), 0);
    /* runs count: negative, 2^31 - 1; hue/saturation count past the end */
    const size_t nruns_at = ndet_at + 2 + 40u * (size_t)((orig[ndet_at] << 8) | orig[ndet_at + 1]) + 4;
    const int64_t bad_runs[] = {-1, 0x7fffffff, 0x40000000};
    for (int i = 0; i < 3; i++) {
        memcpy(g_buf, orig, (size_t)len);
        put_be(g_buf + nruns_at, 4, bad_runs[i]);
        assert_int_not_equal(mvtd_frame_wire_check(g_buf, (uint32_t)len), 0);
    }
    memcpy(g_buf, orig, (size_t)len);
    assert_int_equal(mvtd_frame_wire_check(g_buf, (uint32_t)len), 0);
    /* trailing bytes after a valid message are allowed, as LCM's decoder allows them */
    assert_int_equal(mvtd_frame_wire_check(g_buf, (uint32_t)len + 10), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wire_check_valid_messages_pass_and_decode),
        cmocka_unit_test(test_wire_check_every_truncation_fails),
        cmocka_unit_test(test_wire_check_hostile_counts_and_names_fail),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
