/* firmware-core from C on a Cortex-M4F (QEMU mps2-an386): the C ABI's centroid, tracking
 * window and vision pipeline linked from the no_std staticlib, checked here, reported by
 * semihosting. Built and run by mcu-demo/c/run.sh (in CI). No C library: a vector table, a
 * reset handler, and integer printing of our own. */
#include "vibcam.h"

#include <stdint.h>

/* ---- start-up and semihosting ---------------------------------------------------------- */

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _stack_top;
int main(void);

static int semihost(int op, const void *arg) {
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

static void put(const char *s) { semihost(0x04, s); /* SYS_WRITE0 */ }

static void exit_with(int code) {
    /* SYS_EXIT_EXTENDED: ADP_Stopped_ApplicationExit and the status */
    uint32_t block[2] = {0x20026, (uint32_t)code};
    semihost(0x20, block);
    for (;;) {
    }
}

void reset(void) {
    uint32_t *src = &_sidata, *dst = &_sdata;
    while (dst < &_edata) *dst++ = *src++;
    for (dst = &_sbss; dst < &_ebss; dst++) *dst = 0;
#if defined(__ARM_FP)
    /* the FPU: full access to CP10 and CP11 */
    *(volatile uint32_t *)0xE000ED88 |= 0xFu << 20;
    __asm__ volatile("dsb\n isb");
#endif
    exit_with(main());
}

static void fault(void) { exit_with(99); }

__attribute__((section(".vectors"), used)) static const void *vectors[16] = {
    &_stack_top, (void *)reset, (void *)fault, (void *)fault, (void *)fault, (void *)fault,
    (void *)fault, 0, 0, 0, 0, (void *)fault, (void *)fault, 0, (void *)fault, (void *)fault,
};

/* ---- printing without a C library ------------------------------------------------------ */

static void put_int(long v) {
    char b[24];
    int i = 23;
    int neg = v < 0;
    unsigned long u = neg ? (unsigned long)(-v) : (unsigned long)v;
    b[i] = 0;
    do {
        b[--i] = (char)('0' + u % 10);
        u /= 10;
    } while (u);
    if (neg) b[--i] = '-';
    put(&b[i]);
}

/* v with 6 decimals, rounded half away from zero: the Rust demo's `Fx` format, so that lines
 * the two demos share compare as text */
static void put_fixed(float v) {
    if (v != v) {
        put("NaN");
        return;
    }
    double a = v < 0 ? -(double)v : (double)v;
    if (a >= 1.8e13) {
        put("out-of-range");
        return;
    }
    uint64_t scaled = (uint64_t)(a * 1e6 + 0.5);
    if (v < 0) put("-");
    put_int((long)(scaled / 1000000u));
    put(".");
    char d[7];
    uint32_t f = (uint32_t)(scaled % 1000000u);
    for (int i = 5; i >= 0; i--) {
        d[i] = (char)('0' + f % 10);
        f /= 10;
    }
    d[6] = 0;
    put(d);
}

#ifndef VC_NO_PIPELINE
/* the bits of v, 8 hex digits (the lines compared with the Rust demo's to the last bit) */
static void put_bits(float v) {
    union {
        float f;
        uint32_t u;
    } b;
    char d[9];
    b.f = v;
    for (int i = 7; i >= 0; i--) {
        d[i] = "0123456789abcdef"[b.u & 0xF];
        b.u >>= 4;
    }
    d[8] = 0;
    put(d);
}
#endif

static int failures;
static void check(int ok, const char *what) {
    if (!ok) {
        put("FAIL ");
        put(what);
        put("\n");
        failures++;
    }
}

#ifndef VC_NO_PIPELINE
static float fabsf_(float x) { return x < 0 ? -x : x; }

/* sin and cos by a rotation recurrence in double precision (no libm) */
typedef struct {
    double c, s, dc, ds;
} rotor;
static rotor rotor_new(double step) {
    /* cos and sin of a small step by their series (|step| < 0.5 here) */
    double x2 = step * step;
    double dc = 1 - x2 / 2 + x2 * x2 / 24 - x2 * x2 * x2 / 720 + x2 * x2 * x2 * x2 / 40320;
    double ds = step * (1 - x2 / 6 + x2 * x2 / 120 - x2 * x2 * x2 / 5040 + x2 * x2 * x2 * x2 / 362880);
    rotor r = {1.0, 0.0, dc, ds};
    return r;
}
static void rotor_step(rotor *r) {
    double c = r->c * r->dc - r->s * r->ds;
    r->s = r->s * r->dc + r->c * r->ds;
    r->c = c;
}
#endif

/* ---- stack use ------------------------------------------------------------------------ */

/* The 120 KiB below the caller's stack pointer painted; stack_used(lo) after a call: the
 * deepest word it changed (how much stack the call used, to 4 bytes). */
#ifndef VC_NO_PIPELINE
#define PAINT 0xC0FFEE11u
#define PAINT_BYTES (120 * 1024)
__attribute__((noinline)) static uint32_t *stack_paint(void) {
    uint32_t here;
    uintptr_t top = (uintptr_t)&here - 256;
    uint32_t *lo = (uint32_t *)((uintptr_t)&here - PAINT_BYTES);
    for (volatile uint32_t *q = lo; (uintptr_t)q < top; q++) *q = PAINT;
    return lo;
}
__attribute__((noinline)) static long stack_used(uint32_t *lo) {
    uint32_t here;
    volatile uint32_t *q = lo;
    while ((uintptr_t)q < (uintptr_t)&here && *q == PAINT) q++;
    return (long)((uintptr_t)&here - (uintptr_t)q);
}
#endif

/* ---- the checks ---------------------------------------------------------------------- */

/* Instruction counts (bench.sh): QEMU's marks plugin counts the guest instructions between
 * consecutive calls of this function; each measured item is printed as "bench: LABEL" and
 * enclosed by two calls. */
__attribute__((noinline, used)) void bench_mark(void) { __asm__ volatile("nop"); }
static void bench_begin(const char *label) {
    put("bench: ");
    put(label);
    put("\n");
    bench_mark();
}

#define W 64
#define H 48
static uint8_t frame[W * H];
static vc_tracker_t tracker;
static vc_multi_t multi;
#ifndef VC_NO_PIPELINE
static vc_pipeline_t pipe;
static vc_fdd4_t fdd;
static float adc_second[2048], cam_second[120];
static float fdd_frames[256][4];
#endif

/* a square target of side 2r+1 (integer geometry: its centroid is exact) */
static void draw(int cx, int cy, int r) {
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            frame[y * W + x] = (x >= cx - r && x <= cx + r && y >= cy - r && y <= cy + r) ? 200 : 10;
}

int main(void) {
    vc_centroid_config_t cfg = {50, VC_MODE_BINARY, 0, 0, {0, 0, 0, 0}};
    vc_centroid_t c;
    int status;

    bench_begin("empty");
    bench_mark();
    draw(30, 20, 4);
    bench_begin("centroid, binary, 64 x 48 frame");
    status = vc_centroid_u8(frame, sizeof frame, W, H, W, &cfg, &c);
    bench_mark();
    check(status == VC_OK, "centroid status");
    check(c.cx == 30.0f && c.cy == 20.0f && c.pixels == 81 && c.flags == 0, "centroid");
    put("centroid: (");
    put_fixed(c.cx);
    put(", ");
    put_fixed(c.cy);
    put("), ");
    put_int((long)c.pixels);
    put(" pixels\n");
    check(vc_centroid_u8(0, 0, W, H, W, &cfg, &c) == VC_ERR_NULL, "null pointer status");

    vc_track_config_t tc = {cfg, W, H, 4};
    check(vc_tracker_init(&tracker, &tc) == VC_OK, "tracker init");
    int windowed = 0;
    for (int k = 0; k < 16; k++) {
        vc_roi_t roi;
        draw(12 + 2 * k, 10 + k, 4);
        windowed += vc_tracker_window(&tracker, &roi) == 1;
        if (k == 8) bench_begin("tracker, one 64 x 48 frame in its window (9 x 9 target)");
        for (int y = 0; y < H; y++) vc_tracker_push_row_u8(&tracker, frame + y * W, W);
        status = vc_tracker_finish_frame(&tracker, &c);
        if (k == 8) bench_mark();
        check(status == VC_OK, "tracker frame");
        check(c.cx == (float)(12 + 2 * k) && c.cy == (float)(10 + k), "tracker position");
    }
    check(windowed == 15, "tracker windows");
    put("tracker: 16 frames, ");
    put_int(windowed);
    put(" in a window\n");

    /* the Rust demo's frame (mcu-demo/src/main.rs): 320 x 240, a disk of radius 20 px centred
     * at (171.5, 97) at level 200 on 10, threshold 100; its rows made one at a time and
     * streamed into a tracker, whose first frame is searched whole. The lines printed are the
     * Rust demo's, character for character (mcu-demo/c/same_figures.sh compares them). */
    {
        static uint8_t row[320];
        static const char *names[2] = {"Binary", "Weighted"};
        for (int mode = 0; mode < 2; mode++) {
            vc_centroid_config_t dc = {100, mode == 0 ? VC_MODE_BINARY : VC_MODE_WEIGHTED, 0, 0,
                                       {0, 0, 0, 0}};
            vc_track_config_t dt = {dc, 320, 240, 8};
            uint64_t naive = 0;
            check(vc_tracker_init(&tracker, &dt) == VC_OK, "disk tracker init");
            for (int y = 0; y < 240; y++) {
                for (int x = 0; x < 320; x++) {
                    int dx = 2 * x - 343, dy = 2 * y - 194;
                    row[x] = dx * dx + dy * dy <= 4 * 20 * 20 ? 200 : 10;
                    if (row[x] > 100) naive += mode == 0 ? 1u : (uint64_t)(row[x] - 100);
                }
                vc_tracker_push_row_u8(&tracker, row, 320);
            }
            check(vc_tracker_finish_frame(&tracker, &c) == VC_OK, "disk frame");
            check(c.cx == 171.5f && c.cy == 97.0f && c.flags == 0, "disk centre");
            put("centroid u8  ");
            put(names[mode]);
            put(": (");
            put_fixed(c.cx);
            put(", ");
            put_fixed(c.cy);
            put(") (naive weight ");
            put_int((long)naive);
            put(")\n");
        }
    }

    /* several targets: two squares, their centroids exact */
    {
        vc_target_t t[4];
        uint32_t count = 0;
        uint8_t flags = 0;
        for (int i = 0; i < W * H; i++) frame[i] = 10;
        for (int y = 5; y <= 9; y++)
            for (int x = 5; x <= 9; x++) frame[y * W + x] = 200;
        for (int y = 30; y <= 36; y++)
            for (int x = 40; x <= 46; x++) frame[y * W + x] = 200;
        check(vc_multi_init(&multi, &cfg) == VC_OK, "multi init");
        bench_begin("multi-target, 64 x 48 frame, 2 targets");
        for (int y = 0; y < H; y++) vc_multi_push_row_u8(&multi, frame + y * W, W);
        status = vc_multi_targets(&multi, t, 4, &count, &flags);
        bench_mark();
        check(status == VC_OK && count == 2 && flags == 0, "multi targets");
        int a = t[0].centroid.cx < t[1].centroid.cx ? 0 : 1;
        check(t[a].centroid.cx == 7.0f && t[a].centroid.cy == 7.0f, "first square");
        check(t[1 - a].centroid.cx == 43.0f && t[1 - a].centroid.cy == 33.0f, "second square");
        put("multi: ");
        put_int((long)count);
        put(" targets\n");
    }

#ifndef VC_NO_PIPELINE
    /* output-only: four targets in two modes (7 Hz, shape sin; 23 Hz, shape cos), slowly
     * modulated, a little noise: two peaks, each with its shape (MAC > 0.999) */
    {
        const double pi = 3.14159265358979323846;
        /* sin(pi/2 (k+1)/4) and cos(pi (k+1)/4) */
        const double sh1[4] = {0.38268343236508984, 0.7071067811865476, 0.9238795325112867, 1.0};
        const double sh2[4] = {0.7071067811865476, 0.0, -0.7071067811865476, -1.0};
        rotor m1 = rotor_new(2 * pi * 7.0 / 120.0), m2 = rotor_new(2 * pi * 23.0 / 120.0);
        rotor a1 = rotor_new(0.37 / 120.0), a2 = rotor_new(0.23 / 120.0);
        uint64_t seed = 1;
        uint32_t *lo = stack_paint();
        check(vc_fdd4_init(&fdd, 120.0f) == VC_OK, "fdd init");
        put("stack: vc_fdd4_init used ");
        put_int(stack_used(lo));
        put(" bytes\n");
        for (int i = 0; i < 512 * 8; i++) {
            double a = m1.s * (1.0 + 0.3 * a1.s), b = 0.5 * m2.s * (1.0 + 0.3 * a2.c);
            float *x = fdd_frames[i % 256];
            for (int k = 0; k < 4; k++) {
                seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
                double noise = (double)(seed >> 33) / 2147483648.0 - 0.5;
                x[k] = (float)(a * sh1[k] + b * sh2[k] + 0.01 * noise);
            }
            rotor_step(&m1);
            rotor_step(&m2);
            rotor_step(&a1);
            rotor_step(&a2);
            /* every 256 frames made, pushed: the 15th batch is measured (the library alone) */
            if (i % 256 == 255) {
                int measured = i / 256 == 14;
                if (measured) bench_begin("fdd, 4 targets: 256 frames (one segment of 512 added)");
                for (int j = 0; j < 256; j++) vc_fdd4_push(&fdd, fdd_frames[j]);
                if (measured) bench_mark();
            }
        }
        uint32_t lines[8], count = 0;
        bench_begin("fdd, 4 targets: peaks over 257 lines");
        status = vc_fdd4_peaks(&fdd, 1.0f, 59.0f, 6.0f, 10.0f, lines, 8, &count);
        bench_mark();
        check(status == VC_OK && count == 2, "fdd peaks");
        for (uint32_t p = 0; p < count && p < 2; p++) {
            float hz = 0, s1 = 0;
            vc_complex_t v[4];
            const double *sh = p == 0 ? sh1 : sh2;
            check(vc_fdd4_line(&fdd, lines[p], &hz, &s1, v) == VC_OK, "fdd line");
            double dre = 0, dim = 0, vv = 0, ss = 0;
            for (int k = 0; k < 4; k++) {
                dre += v[k].re * sh[k];
                dim += v[k].im * sh[k];
                vv += v[k].re * v[k].re + v[k].im * v[k].im;
                ss += sh[k] * sh[k];
            }
            double mac = (dre * dre + dim * dim) / (vv * ss);
            check(fabsf_(hz - (p == 0 ? 7.0f : 23.0f)) <= 120.0f / 512.0f && mac > 0.999,
                  "fdd peak and shape");
            put("fdd: peak at ");
            put_fixed(hz);
            put(" Hz, MAC ");
            put_fixed((float)mac);
            put("\n");
        }
    }

    /* a 7 Hz motion: ADC acceleration 5 sin(wt) m/s^2, camera displacement whose acceleration
     * leads it by a quarter period (mm): H1 = i at 7 Hz */
    const double pi = 3.14159265358979323846, w = 2.0 * pi * 7.0;
    vc_pipeline_config_t pc = {120, 2048, 1e-3f, 0.0f};
    {
        uint32_t *lo = stack_paint();
        check(vc_pipeline_init(&pipe, &pc) == VC_OK, "pipeline init");
        put("stack: vc_pipeline_init used ");
        put_int(stack_used(lo));
        put(" bytes\n");
    }
    rotor adc_r = rotor_new(w / 2048.0), cam_r = rotor_new(w / 120.0);
    /* each second's inputs are made before it is pushed, so that the measured second is the
     * library's work alone (the test signal's double arithmetic is software on an M4F) */
    unsigned sent = 0;
    int pushed_ok = 1;
    for (unsigned second = 0; second < 6; second++) {
        for (unsigned i = 0; i < 2048; i++) {
            adc_second[i] = (float)(5.0 * adc_r.s);
            rotor_step(&adc_r);
        }
        for (unsigned k = 0; k < 120; k++) {
            cam_second[k] = (float)(-5.0 * cam_r.c / (w * w) * 1e3);
            rotor_step(&cam_r);
        }
        if (second == 5) bench_begin("pipeline, one second: 120 frames and 2048 ADC samples in, H1 updated");
        unsigned done = 0;
        for (unsigned k = 0; k < 120; k++) {
            unsigned upto = ((120 * second + k + 1) * 2048 + 119) / 120 - 2048 * second;
            pushed_ok &= vc_pipeline_push_adc(&pipe, adc_second + done, upto - done) == VC_OK;
            pushed_ok &= vc_pipeline_push_frame(&pipe, cam_second[k]) == VC_OK;
            done = upto;
        }
        if (second == 5) bench_mark();
        sent += done;
    }
    check(pushed_ok && sent == 6 * 2048, "every push taken");
    float re = 0, im = 0, df = 0;
    uint32_t bins = 0;
    vc_peak_t pk;
    check(vc_pipeline_h1(&pipe, 7, &re, &im, &bins, &df) == VC_OK, "h1");
    check(bins == 1025 && df == 1.0f, "bins");
    check(fabsf_(re) < 0.02f && fabsf_(im - 1.0f) < 0.02f, "H1 at 7 Hz");
    check(vc_pipeline_peak(&pipe, 6.5f, 7.5f, &pk) == VC_OK, "peak");
    check(fabsf_(pk.amplitude - 1.0f) < 0.02f, "peak amplitude");
    /* the line the Rust demo prints for the same scenario (check_pipeline_as_c) */
    put("pipeline: H1(7 Hz) = ");
    put_fixed(re);
    put(" + ");
    put_fixed(im);
    put("i after ");
    put_int((long)pk.segments);
    put(" segments; peak ");
    put_fixed(pk.f_hz);
    put(" Hz, |H1| ");
    put_fixed(pk.amplitude);
    put("\npipeline: H1(7 Hz) bits ");
    put_bits(re);
    put(" ");
    put_bits(im);
    put(", |H1| bits ");
    put_bits(pk.amplitude);
    put("\n");
#else
    put("pipeline: not built (VC_NO_PIPELINE: its 57 600 bytes do not fit this RAM)\n");
#endif

    if (failures) {
        put_int(failures);
        put(" checks failed\n");
        return 1;
    }
    put("C demo: all checks passed\n");
    return 0;
}
