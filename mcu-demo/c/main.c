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

/* v with 4 decimals */
static void put_fixed(float v) {
    long scaled = (long)(v * 10000.0f + (v < 0 ? -0.5f : 0.5f));
    if (scaled < 0) {
        put("-");
        scaled = -scaled;
    }
    put_int(scaled / 10000);
    put(".");
    char d[5];
    long f = scaled % 10000;
    for (int i = 3; i >= 0; i--) {
        d[i] = (char)('0' + f % 10);
        f /= 10;
    }
    d[4] = 0;
    put(d);
}

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
    /* a 7 Hz motion: ADC acceleration 5 sin(wt) m/s^2, camera displacement whose acceleration
     * leads it by a quarter period (mm): H1 = i at 7 Hz */
    const double pi = 3.14159265358979323846, w = 2.0 * pi * 7.0;
    vc_pipeline_config_t pc = {120, 2048, 1e-3f, 0.0f};
    check(vc_pipeline_init(&pipe, &pc) == VC_OK, "pipeline init");
    rotor adc_r = rotor_new(w / 2048.0), cam_r = rotor_new(w / 120.0);
    float adc[32];
    unsigned sent = 0;
    for (unsigned k = 0; k < 6 * 120; k++) {
        if (k == 5 * 120) bench_begin("pipeline, one second: 120 frames and 2048 ADC samples in, H1 updated");
        unsigned upto = ((k + 1) * 2048 + 119) / 120, n = 0;
        for (; sent < upto; sent++) {
            adc[n++] = (float)(5.0 * adc_r.s);
            rotor_step(&adc_r);
        }
        check(vc_pipeline_push_adc(&pipe, adc, n) == VC_OK, "push adc");
        check(vc_pipeline_push_frame(&pipe, (float)(-5.0 * cam_r.c / (w * w) * 1e3)) == VC_OK,
              "push frame");
        rotor_step(&cam_r);
        if (k == 6 * 120 - 1) bench_mark();
    }
    float re = 0, im = 0, df = 0;
    uint32_t bins = 0;
    vc_peak_t pk;
    check(vc_pipeline_h1(&pipe, 7, &re, &im, &bins, &df) == VC_OK, "h1");
    check(bins == 1025 && df == 1.0f, "bins");
    check(fabsf_(re) < 0.02f && fabsf_(im - 1.0f) < 0.02f, "H1 at 7 Hz");
    check(vc_pipeline_peak(&pipe, 6.0f, 8.0f, &pk) == VC_OK, "peak");
    check(fabsf_(pk.amplitude - 1.0f) < 0.02f, "peak amplitude");
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
