/* The C ABI from C: firmware-core's centroid and tracking window against a naive centroid
 * computed here, on frames drawn here. Built and run by firmware-core-ffi/c/run.sh (in CI):
 * gcc -std=c99 -Wall -Wextra -Werror -pedantic, linked against the host staticlib. */
#include "vibcam.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define W 64
#define H 48

static uint8_t frame[W * H];
static vc_tracker_t tracker; /* caller-owned state, in static memory */
static vc_pipeline_t pipe;
static vc_multi_t multi;
static vc_fdd4_t fdd;

/* a disk of radius r at (cx, cy): 200 inside, 10 outside, 100 on a one-pixel ramp */
static void draw(double cx, double cy, double r) {
    for (int y = 0; y < H; y++) {
        for (int x = 0; x < W; x++) {
            double d = sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy));
            frame[y * W + x] = d < r - 0.5 ? 200 : (d < r + 0.5 ? 100 : 10);
        }
    }
}

/* the reference: sums over the pixels above t, weight 1 (binary) or value - t (weighted) */
static void naive(uint16_t t, int weighted, double *cx, double *cy, unsigned long *n) {
    double w = 0, sx = 0, sy = 0;
    *n = 0;
    for (int y = 0; y < H; y++) {
        for (int x = 0; x < W; x++) {
            int v = frame[y * W + x];
            if (v > t) {
                double k = weighted ? (double)(v - t) : 1.0;
                w += k;
                sx += k * x;
                sy += k * y;
                (*n)++;
            }
        }
    }
    *cx = sx / w;
    *cy = sy / w;
}

static int failures = 0;
#define CHECK(cond, ...)                                                                     \
    do {                                                                                     \
        if (!(cond)) {                                                                       \
            printf("FAIL %s:%d: ", __FILE__, __LINE__);                                      \
            printf(__VA_ARGS__);                                                             \
            printf("\n");                                                                    \
            failures++;                                                                      \
        }                                                                                    \
    } while (0)

int main(void) {
    vc_centroid_config_t cfg;
    vc_centroid_t c;
    memset(&cfg, 0, sizeof cfg);

    /* the centroid, both modes, against the naive sums */
    draw(30.3, 20.7, 6.0);
    for (int mode = 0; mode < 2; mode++) {
        double rx, ry;
        unsigned long n;
        cfg.threshold = 50;
        cfg.mode = mode == 0 ? VC_MODE_BINARY : VC_MODE_WEIGHTED;
        int s = vc_centroid_u8(frame, sizeof frame, W, H, W, &cfg, &c);
        naive(50, mode, &rx, &ry, &n);
        CHECK(s == VC_OK, "status %d", (int)s);
        CHECK(c.pixels == n, "pixels %lu vs %lu", (unsigned long)c.pixels, n);
        CHECK(fabs(c.cx - rx) < 1e-4 && fabs(c.cy - ry) < 1e-4, "mode %d: (%f, %f) vs (%f, %f)",
              mode, c.cx, c.cy, rx, ry);
        CHECK(c.flags == 0, "flags %d", c.flags);
        printf("centroid mode %d: (%.4f, %.4f), %lu pixels\n", mode, c.cx, c.cy,
               (unsigned long)c.pixels);
    }

    /* errors are statuses */
    CHECK(vc_centroid_u8(NULL, 0, W, H, W, &cfg, &c) == VC_ERR_NULL, "null pixels");
    CHECK(vc_centroid_u8(frame, sizeof frame - 1, W, H, W, &cfg, &c) == VC_ERR_FRAME, "short");
    cfg.mode = 9;
    CHECK(vc_centroid_u8(frame, sizeof frame, W, H, W, &cfg, &c) == VC_ERR_CONFIG, "mode");
    cfg.mode = VC_MODE_BINARY;
    CHECK(vc_tracker_finish_frame(&tracker, &c) == VC_ERR_STATE, "uninitialised tracker");

    /* the tracking window, fed row by row, on a disk moving 1.5 px per frame */
    vc_track_config_t tc;
    memset(&tc, 0, sizeof tc);
    tc.centroid.threshold = 50;
    tc.centroid.mode = VC_MODE_BINARY;
    tc.width = W;
    tc.height = H;
    tc.margin = 4;
    CHECK(vc_tracker_init(&tracker, &tc) == VC_OK, "init");
    int windowed = 0;
    for (int k = 0; k < 16; k++) {
        double rx, ry;
        unsigned long n;
        vc_roi_t roi;
        draw(15.0 + 1.5 * k, 12.0 + 1.0 * k, 5.0);
        windowed += vc_tracker_window(&tracker, &roi) == 1;
        for (int y = 0; y < H; y++) {
            CHECK(vc_tracker_push_row_u8(&tracker, frame + y * W, W) == VC_OK, "row %d", y);
        }
        CHECK(vc_tracker_finish_frame(&tracker, &c) == VC_OK, "finish");
        naive(50, 0, &rx, &ry, &n);
        CHECK(fabs(c.cx - rx) < 1e-4 && fabs(c.cy - ry) < 1e-4 && c.pixels == n,
              "frame %d: (%f, %f) vs (%f, %f)", k, c.cx, c.cy, rx, ry);
    }
    CHECK(windowed == 15, "%d frames read in a window", windowed);
    printf("tracker: 16 frames, %d in a window, last (%.4f, %.4f)\n", windowed, c.cx, c.cy);
    printf("sizeof(vc_tracker_t) = %u\n", (unsigned)sizeof(vc_tracker_t));

    /* several targets: two squares, their centroids exact, in either order */
    {
        vc_target_t t[4];
        uint32_t count = 0;
        uint8_t flags = 0;
        for (int i = 0; i < W * H; i++) frame[i] = 10;
        for (int y = 5; y <= 9; y++)
            for (int x = 5; x <= 9; x++) frame[y * W + x] = 200;
        for (int y = 30; y <= 36; y++)
            for (int x = 40; x <= 46; x++) frame[y * W + x] = 200;
        cfg.threshold = 50;
        cfg.mode = VC_MODE_BINARY;
        CHECK(vc_multi_init(&multi, &cfg) == VC_OK, "multi init");
        for (int y = 0; y < H; y++) vc_multi_push_row_u8(&multi, frame + y * W, W);
        CHECK(vc_multi_targets(&multi, t, 4, &count, &flags) == VC_OK, "targets");
        CHECK(count == 2 && flags == 0, "%u targets, flags %d", (unsigned)count, flags);
        int a = t[0].centroid.cx < t[1].centroid.cx ? 0 : 1;
        CHECK(t[a].centroid.cx == 7.0f && t[a].centroid.cy == 7.0f && t[a].centroid.pixels == 25,
              "first square (%f, %f)", t[a].centroid.cx, t[a].centroid.cy);
        CHECK(t[1 - a].centroid.cx == 43.0f && t[1 - a].centroid.cy == 33.0f &&
                  t[1 - a].x_min == 40 && t[1 - a].y_max == 36,
              "second square (%f, %f)", t[1 - a].centroid.cx, t[1 - a].centroid.cy);
        CHECK(vc_multi_next_frame(&multi) == VC_OK, "next frame");
        CHECK(vc_multi_targets(&multi, NULL, 0, &count, &flags) == VC_OK && count == 0 &&
                  (flags & VC_FLAG_EMPTY),
              "empty after next frame");
        printf("multi: 2 targets at (%.1f, %.1f) and (%.1f, %.1f)\n", t[a].centroid.cx,
               t[a].centroid.cy, t[1 - a].centroid.cx, t[1 - a].centroid.cy);
    }

    /* output-only: four targets moving in two modes (7 Hz, shape sin; 23 Hz, shape cos),
     * slowly modulated, with a little noise: two peaks, shapes with MAC > 0.999 */
    {
        const double pi = 3.14159265358979323846;
        double sh1[4], sh2[4];
        uint64_t seed = 1;
        for (int k = 0; k < 4; k++) {
            sh1[k] = sin(0.5 * pi * (k + 1) / 4.0);
            sh2[k] = cos(pi * (k + 1) / 4.0);
        }
        CHECK(vc_fdd4_init(&fdd, 120.0f) == VC_OK, "fdd init");
        for (int i = 0; i < 512 * 8; i++) {
            double t = i / 120.0;
            double a = sin(2 * pi * 7.0 * t) * (1.0 + 0.3 * sin(0.37 * t));
            double b = 0.5 * sin(2 * pi * 23.0 * t) * (1.0 + 0.3 * cos(0.23 * t));
            float x[4];
            for (int k = 0; k < 4; k++) {
                seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
                double noise = (double)(seed >> 33) / 2147483648.0 - 0.5;
                x[k] = (float)(a * sh1[k] + b * sh2[k] + 0.01 * noise);
            }
            vc_fdd4_push(&fdd, x);
        }
        uint32_t lines[8], count = 0;
        CHECK(vc_fdd4_peaks(&fdd, 1.0f, 59.0f, 6.0f, 10.0f, lines, 8, &count) == VC_OK, "peaks");
        CHECK(count == 2, "%u peaks", (unsigned)count);
        for (uint32_t p = 0; p < count && p < 2; p++) {
            float hz = 0, s1 = 0;
            vc_complex_t v[4];
            const double *sh = p == 0 ? sh1 : sh2;
            CHECK(vc_fdd4_line(&fdd, lines[p], &hz, &s1, v) == VC_OK, "line");
            double dre = 0, dim = 0, vv = 0, ss = 0;
            for (int k = 0; k < 4; k++) {
                dre += v[k].re * sh[k];
                dim += v[k].im * sh[k];
                vv += v[k].re * v[k].re + v[k].im * v[k].im;
                ss += sh[k] * sh[k];
            }
            double mac = (dre * dre + dim * dim) / (vv * ss);
            CHECK(fabs(hz - (p == 0 ? 7.0 : 23.0)) <= 120.0 / 512.0 && mac > 0.999,
                  "peak %u at %f Hz, MAC %f", (unsigned)p, hz, mac);
            printf("fdd: peak at %.3f Hz, MAC %.6f\n", hz, mac);
        }
    }

    /* the vision channel: a 7 Hz motion seen by the ADC (m/s^2) and the camera (mm, its
     * acceleration a quarter period ahead), 120 fps and 2048 Hz for 6 s: H1 = i at 7 Hz */
    {
        const double pi = 3.14159265358979323846, f = 7.0, w = 2.0 * pi * f;
        vc_pipeline_config_t pc = {120, 2048, 1e-3f, 0.0f};
        float adc[32];
        unsigned sent = 0;
        CHECK(vc_pipeline_init(&pipe, &pc) == VC_OK, "pipeline init");
        for (unsigned k = 0; k < 6 * 120; k++) {
            unsigned upto = ((k + 1) * 2048 + 119) / 120, n = 0;
            for (; sent < upto; sent++) {
                adc[n++] = (float)(5.0 * sin(w * sent / 2048.0));
            }
            CHECK(vc_pipeline_push_adc(&pipe, adc, n) == VC_OK, "adc before frame %u", k);
            CHECK(vc_pipeline_push_frame(&pipe, (float)(-5.0 * cos(w * k / 120.0) / (w * w) * 1e3)) ==
                      VC_OK,
                  "frame %u", k);
        }
        float re = 0, im = 0, df = 0;
        uint32_t bins = 0;
        CHECK(vc_pipeline_h1(&pipe, 7, &re, &im, &bins, &df) == VC_OK, "h1");
        CHECK(bins == 1025 && df == 1.0f, "%u bins of %f Hz", (unsigned)bins, df);
        CHECK(fabs(re) < 0.02 && fabs(im - 1.0) < 0.02, "H1(7 Hz) = %f + %fi", re, im);
        vc_peak_t pk;
        CHECK(vc_pipeline_peak(&pipe, 6.0f, 8.0f, &pk) == VC_OK, "peak");
        CHECK(fabs(pk.amplitude - 1.0) < 0.02 && pk.segments >= 5, "peak %f after %u segments",
              pk.amplitude, (unsigned)pk.segments);
        printf("pipeline: H1(7 Hz) = %.4f %+.4fi after %u segments; sizeof(vc_pipeline_t) = %u\n",
               re, im, (unsigned)pk.segments, (unsigned)sizeof(vc_pipeline_t));
    }

    if (failures) {
        printf("%d failures\n", failures);
        return 1;
    }
    printf("C ABI: all checks passed\n");
    return 0;
}
