/*
 * mvt_config.h - compile-time capacities and the real type of the mvtrack core.
 *
 * Every array in the core is sized by these macros; every input count is checked against them
 * and the excess is counted and dropped, never written past. Override with -D on the compiler
 * command line (CMake: MVT_MAX_CAMERAS etc. cache variables, MVT_USE_DOUBLE option).
 */
#ifndef MVT_CONFIG_H
#define MVT_CONFIG_H

/* Cameras in the rig (bits of track_t.cameras_used, so at most 31). Default 16, range 1..31. */
#ifndef MVT_MAX_CAMERAS
#define MVT_MAX_CAMERAS 16
#endif
#if MVT_MAX_CAMERAS < 1 || MVT_MAX_CAMERAS > 31
#error "MVT_MAX_CAMERAS must be in 1..31"
#endif

/* Simultaneous tracks (tentative + confirmed + coasting). Default 32, range 1..1024. */
#ifndef MVT_MAX_TARGETS
#define MVT_MAX_TARGETS 32
#endif
#if MVT_MAX_TARGETS < 1 || MVT_MAX_TARGETS > 1024
#error "MVT_MAX_TARGETS must be in 1..1024"
#endif

/* Detections kept per camera and frame; the excess is counted and dropped. Default 64, 1..1024. */
#ifndef MVT_MAX_DETECTIONS
#define MVT_MAX_DETECTIONS 64
#endif
#if MVT_MAX_DETECTIONS < 1 || MVT_MAX_DETECTIONS > 1024
#error "MVT_MAX_DETECTIONS must be in 1..1024"
#endif

/* Static occluders the rig may declare (furniture, pillars: boxes in the room). Default 16,
 * range 0..256. */
#ifndef MVT_MAX_OCCLUDERS
#define MVT_MAX_OCCLUDERS 16
#endif
#if MVT_MAX_OCCLUDERS < 0 || MVT_MAX_OCCLUDERS > 256
#error "MVT_MAX_OCCLUDERS must be in 0..256"
#endif

/* Particles per target in the particle-filter tracker (mvt_pft). Default 1000, range 16..65535. */
#ifndef MVT_MAX_PARTICLES
#define MVT_MAX_PARTICLES 1000
#endif
#if MVT_MAX_PARTICLES < 16 || MVT_MAX_PARTICLES > 65535
#error "MVT_MAX_PARTICLES must be in 16..65535"
#endif

/* Pixels of one camera's foreground mask (mask_width * mask_height). Default 110592 (384 x 288,
 * half of 768 x 576; the usual quarter resolution needs 27648), range 16..4194304. */
#ifndef MVT_MAX_MASK_PIXELS
#define MVT_MAX_MASK_PIXELS 110592
#endif
#if MVT_MAX_MASK_PIXELS < 16 || MVT_MAX_MASK_PIXELS > 4194304
#error "MVT_MAX_MASK_PIXELS must be in 16..4194304"
#endif

/* Real type: float (default, for FPU-equipped microcontrollers) or double (MVT_USE_DOUBLE=1). */
#ifndef MVT_USE_DOUBLE
#define MVT_USE_DOUBLE 0
#endif

#if MVT_USE_DOUBLE
typedef double mvt_real;
#define MVT_SQRT sqrt
#define MVT_FABS fabs
#define MVT_SIN sin
#define MVT_COS cos
#define MVT_ATAN2 atan2
#define MVT_EXP exp
#define MVT_LOG log
#define MVT_ERFC erfc
#define MVT_EPS 2.220446049250313e-16
#else
typedef float mvt_real;
#define MVT_SQRT sqrtf
#define MVT_FABS fabsf
#define MVT_SIN sinf
#define MVT_COS cosf
#define MVT_ATAN2 atan2f
#define MVT_EXP expf
#define MVT_LOG logf
#define MVT_ERFC erfcf
#define MVT_EPS 1.1920929e-7f
#endif

/* A literal in the real type: MVT_R(0.5) is 0.5f in float builds, 0.5 in double builds. */
#define MVT_R(x) ((mvt_real)(x))

#endif /* MVT_CONFIG_H */
