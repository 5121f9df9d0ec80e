#pragma once
/* Times mvtrack-detect's per-frame work on `video` with the rig at `rig_path`; prints two JSON lines
 * (decode excluded, included). Returns 0, or -1 when the video or rig cannot be read. */
int bench_detect(const char *video, const char *rig_path);
