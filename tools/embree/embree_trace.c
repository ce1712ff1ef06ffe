/* embree_trace: Intel Embree 3's own C API on strata's ray files, the
 * anchor of strata's performance comparison (docs/embree.md).
 *
 *   embree_trace MESH.tris RAYS.bin [--hits HITS.bin] [--occlusion] [--packet | --stream]
 *                [--robust] [--quality low|medium|high] [--threads N] [--repeats R]
 *                [--first F --count C] [--isa ISA] [--verbose]
 *   embree_trace MESH.tris RAYS.bin --serve [--robust] [--quality Q] [--threads N] [--verbose]
 *   ... [--instances PLACES.csv]
 *
 * MESH.tris (little-endian, no padding): u32 vertex count, u32 triangle
 * count, vertex count x 3 f32 positions, triangle count x 3 u32 indices;
 * triangle i of MESH.tris is primitive i, as triangle i of the mesh file is
 * for strata (`strata bench` and tools/bench_embree.py write it in strata's
 * file order). RAYS.bin is `strata rays`'s format: records of
 * 8 f32, ox oy oz dx dy dz tmin tmax. HITS.bin is `strata trace --hits`'s:
 * per ray t (f32, +inf on a miss), prim (u32, u32::MAX on a miss), u, v; with
 * --occlusion, t = 0, prim = 0 for an occluded ray, else the miss record.
 *
 * With --instances, MESH.tris is placed once per line of PLACES.csv (a
 * row-major 3x4 object-to-world matrix, twelve numbers separated by commas
 * or spaces; blank lines and lines starting with '#' skipped: strata's
 * `instances =` file) as Embree instances of one scene holding the mesh,
 * and a hit's prim is instID * T + primID for a mesh of T triangles:
 * strata's id of that triangle were every instance a copy
 * (`strata trace SCENE.toml`).
 *
 * The scene is one triangle geometry over the caller's buffers (shared, so
 * Embree's own memory is what the memory monitor counts), built at the
 * requested quality (default high: spatial splits for triangles) with
 * RTC_SCENE_FLAG_ROBUST if --robust. Tracing is a plain loop of
 * rtcIntersect1 / rtcOccluded1 (or rtcIntersect8 / rtcOccluded8 over
 * consecutive groups of 8 rays with --packet, or rtcIntersect1M /
 * rtcOccluded1M, Embree's stream API, over each chunk of rays with --stream)
 * writing one hit record per
 * ray, on --threads threads (0: all cores) taking chunks of 256 rays from a
 * shared counter. Like `strata trace`, only tracing is timed: loading and
 * building are not, nor is starting the threads; --repeats passes, the
 * median reported.
 *
 * One-shot, it prints one line in `strata trace`'s format ("... in S s =
 * X Mrays/s on N threads (load L s, BVH B s) -> HITS"), so one parser reads
 * both. With --serve it builds once, prints
 *   ready TRIANGLES BUILD_SECONDS EMBREE_BYTES PEAK_BYTES
 * and then answers each line "FIRST COUNT closest|occlusion single|packet|stream
 * THREADS" on stdin with "SECONDS HITS" (one pass over rays FIRST..FIRST +
 * COUNT), until end of input: `strata bench` drives it that way so that its
 * passes and Embree's can alternate without building twice. With --verbose
 * (Embree's verbose=2) what Embree prints while it builds, the tree and the
 * kernels it chose among them, goes to stderr in --serve mode.
 */
#define _GNU_SOURCE
#include <embree3/rtcore.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define CHUNK 256

static void die(const char *what, const char *why) {
    fprintf(stderr, "error: %s: %s\n", what, why);
    exit(2);
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void *read_file(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    if (!f) die(path, strerror(errno));
    if (fseek(f, 0, SEEK_END) != 0) die(path, strerror(errno));
    long n = ftell(f);
    if (n < 0) die(path, strerror(errno));
    rewind(f);
    /* 16 spare bytes: Embree reads vertex buffers with 16-byte loads. */
    char *data = aligned_alloc(64, ((size_t)n + 16 + 63) / 64 * 64);
    if (!data) die(path, "out of memory");
    if (n && fread(data, 1, (size_t)n, f) != (size_t)n) die(path, "short read");
    fclose(f);
    memset(data + n, 0, 16);
    *size = (size_t)n;
    return data;
}

/* Embree's own allocations, through the device's memory monitor. */
static _Atomic long long embree_bytes, embree_peak;

static bool monitor(void *user, ssize_t bytes, bool post) {
    (void)user;
    (void)post;
    long long now_bytes = atomic_fetch_add(&embree_bytes, bytes) + bytes;
    long long peak = atomic_load(&embree_peak);
    while (now_bytes > peak && !atomic_compare_exchange_weak(&embree_peak, &peak, now_bytes)) {
    }
    return true;
}

static void on_error(void *user, enum RTCError code, const char *message) {
    (void)user;
    fprintf(stderr, "error: Embree %d: %s\n", (int)code, message ? message : "");
    exit(3);
}

typedef struct {
    RTCScene scene;
    const float *rays; /* 8 f32 per ray */
    float *hits;       /* 4 x 32 bits per ray, or NULL */
    size_t first, count;
    int occlusion, packet, stream;
    _Atomic size_t next;
    _Atomic size_t found;
} Job;

/* Triangles of the instanced mesh, or 0 without --instances. */
static uint32_t instanced_tris;

/* A hit's primitive as strata numbers it (see --instances). */
static inline uint32_t hit_prim(unsigned inst, unsigned prim) {
    if (!instanced_tris || inst == RTC_INVALID_GEOMETRY_ID) return prim;
    return inst * instanced_tris + prim;
}

static inline void write_hit(float *out, float t, uint32_t prim, float u, float v) {
    out[0] = t;
    memcpy(out + 1, &prim, 4);
    out[2] = u;
    out[3] = v;
}

static void trace_single(Job *job, size_t lo, size_t hi, size_t *found) {
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (size_t i = lo; i < hi; i++) {
        const float *r = job->rays + 8 * i;
        float *out = job->hits ? job->hits + 4 * i : NULL;
        if (job->occlusion) {
            struct RTCRay ray = {
                .org_x = r[0], .org_y = r[1], .org_z = r[2], .tnear = r[6],
                .dir_x = r[3], .dir_y = r[4], .dir_z = r[5], .time = 0.0f,
                .tfar = r[7], .mask = 0xffffffffu, .id = 0, .flags = 0,
            };
            rtcOccluded1(job->scene, &context, &ray);
            int occluded = ray.tfar == -INFINITY;
            *found += occluded;
            if (out) write_hit(out, occluded ? 0.0f : INFINITY, occluded ? 0u : 0xffffffffu, 0.0f, 0.0f);
        } else {
            struct RTCRayHit rh;
            rh.ray = (struct RTCRay){
                .org_x = r[0], .org_y = r[1], .org_z = r[2], .tnear = r[6],
                .dir_x = r[3], .dir_y = r[4], .dir_z = r[5], .time = 0.0f,
                .tfar = r[7], .mask = 0xffffffffu, .id = 0, .flags = 0,
            };
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(job->scene, &context, &rh);
            int hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            *found += hit;
            if (out) {
                if (hit)
                    write_hit(out, rh.ray.tfar, hit_prim(rh.hit.instID[0], rh.hit.primID), rh.hit.u, rh.hit.v);
                else
                    write_hit(out, INFINITY, 0xffffffffu, 0.0f, 0.0f);
            }
        }
    }
}

/* Consecutive groups of up to 8 rays as one packet each. */
static void trace_packets(Job *job, size_t lo, size_t hi, size_t *found) {
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (size_t base = lo; base < hi; base += 8) {
        int n = hi - base < 8 ? (int)(hi - base) : 8;
        RTC_ALIGN(32) int valid[8];
        RTC_ALIGN(32) struct RTCRayHit8 rh;
        for (int k = 0; k < 8; k++) {
            const float *r = job->rays + 8 * (base + (k < n ? k : 0));
            valid[k] = k < n ? -1 : 0;
            rh.ray.org_x[k] = r[0];
            rh.ray.org_y[k] = r[1];
            rh.ray.org_z[k] = r[2];
            rh.ray.tnear[k] = r[6];
            rh.ray.dir_x[k] = r[3];
            rh.ray.dir_y[k] = r[4];
            rh.ray.dir_z[k] = r[5];
            rh.ray.time[k] = 0.0f;
            rh.ray.tfar[k] = r[7];
            rh.ray.mask[k] = 0xffffffffu;
            rh.ray.id[k] = 0;
            rh.ray.flags[k] = 0;
            rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
        if (job->occlusion) {
            rtcOccluded8(valid, job->scene, &context, &rh.ray);
        } else {
            rtcIntersect8(valid, job->scene, &context, &rh);
        }
        for (int k = 0; k < n; k++) {
            float *out = job->hits ? job->hits + 4 * (base + k) : NULL;
            if (job->occlusion) {
                int occluded = rh.ray.tfar[k] == -INFINITY;
                *found += occluded;
                if (out) write_hit(out, occluded ? 0.0f : INFINITY, occluded ? 0u : 0xffffffffu, 0.0f, 0.0f);
            } else {
                int hit = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
                *found += hit;
                if (out) {
                    if (hit)
                        write_hit(out, rh.ray.tfar[k], hit_prim(rh.hit.instID[0][k], rh.hit.primID[k]), rh.hit.u[k],
                                  rh.hit.v[k]);
                    else
                        write_hit(out, INFINITY, 0xffffffffu, 0.0f, 0.0f);
                }
            }
        }
    }
}

/* Each chunk of rays through Embree's stream API (rtcIntersect1M /
 * rtcOccluded1M, array of structures, the default incoherent context): the
 * rays handed over together, for Embree to trace them as it finds best. */
static void trace_stream(Job *job, size_t lo, size_t hi, size_t *found) {
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTC_ALIGN(64) struct RTCRayHit rh[CHUNK];
    size_t n = hi - lo;
    for (size_t k = 0; k < n; k++) {
        const float *r = job->rays + 8 * (lo + k);
        rh[k].ray = (struct RTCRay){
            .org_x = r[0], .org_y = r[1], .org_z = r[2], .tnear = r[6],
            .dir_x = r[3], .dir_y = r[4], .dir_z = r[5], .time = 0.0f,
            .tfar = r[7], .mask = 0xffffffffu, .id = 0, .flags = 0,
        };
        rh[k].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh[k].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    }
    if (job->occlusion)
        rtcOccluded1M(job->scene, &context, &rh[0].ray, (unsigned)n, sizeof rh[0]);
    else
        rtcIntersect1M(job->scene, &context, rh, (unsigned)n, sizeof rh[0]);
    for (size_t k = 0; k < n; k++) {
        float *out = job->hits ? job->hits + 4 * (lo + k) : NULL;
        if (job->occlusion) {
            int occluded = rh[k].ray.tfar == -INFINITY;
            *found += occluded;
            if (out) write_hit(out, occluded ? 0.0f : INFINITY, occluded ? 0u : 0xffffffffu, 0.0f, 0.0f);
        } else {
            int hit = rh[k].hit.geomID != RTC_INVALID_GEOMETRY_ID;
            *found += hit;
            if (out) {
                if (hit)
                    write_hit(out, rh[k].ray.tfar, hit_prim(rh[k].hit.instID[0], rh[k].hit.primID), rh[k].hit.u,
                              rh[k].hit.v);
                else
                    write_hit(out, INFINITY, 0xffffffffu, 0.0f, 0.0f);
            }
        }
    }
}

static void *worker(void *arg) {
    Job *job = arg;
    size_t found = 0;
    for (;;) {
        size_t lo = atomic_fetch_add(&job->next, CHUNK);
        if (lo >= job->count) break;
        size_t hi = lo + CHUNK < job->count ? lo + CHUNK : job->count;
        if (job->packet)
            trace_packets(job, job->first + lo, job->first + hi, &found);
        else if (job->stream)
            trace_stream(job, job->first + lo, job->first + hi, &found);
        else
            trace_single(job, job->first + lo, job->first + hi, &found);
    }
    atomic_fetch_add(&job->found, found);
    return NULL;
}

/* One pass; returns its seconds. Threads are started before the clock and
 * wait at a barrier, so starting them is not timed. */
typedef struct {
    Job *job;
    pthread_barrier_t *start, *end;
} Worker;

static void *barrier_worker(void *arg) {
    Worker *w = arg;
    pthread_barrier_wait(w->start);
    worker(w->job);
    pthread_barrier_wait(w->end);
    return NULL;
}

static double trace_pass(Job *job, int threads) {
    atomic_store(&job->next, 0);
    atomic_store(&job->found, 0);
    if (threads <= 1) {
        double t0 = now();
        worker(job);
        return now() - t0;
    }
    pthread_barrier_t start, end;
    pthread_barrier_init(&start, NULL, (unsigned)threads);
    pthread_barrier_init(&end, NULL, (unsigned)threads);
    pthread_t *ids = calloc((size_t)threads, sizeof *ids);
    Worker w = {job, &start, &end};
    for (int i = 1; i < threads; i++)
        if (pthread_create(&ids[i], NULL, barrier_worker, &w) != 0) die("threads", "cannot start");
    pthread_barrier_wait(&start);
    double t0 = now();
    worker(job);
    pthread_barrier_wait(&end);
    double seconds = now() - t0;
    for (int i = 1; i < threads; i++) pthread_join(ids[i], NULL);
    pthread_barrier_destroy(&start);
    pthread_barrier_destroy(&end);
    free(ids);
    return seconds;
}

/* A whole decimal number in [lo, hi], else the usage message. */
static long long number(const char *text, long long lo, long long hi) {
    char *end;
    errno = 0;
    long long n = strtoll(text, &end, 10);
    if (errno || end == text || *end || n < lo || n > hi) {
        fprintf(stderr, "error: '%s' is not a number in [%lld, %lld]\n", text, lo, hi);
        exit(2);
    }
    return n;
}

/* The placements of an instances file: 12 floats per matrix, *n of them. */
static float *read_instances(const char *path, size_t *n) {
    FILE *f = fopen(path, "r");
    if (!f) die(path, strerror(errno));
    size_t cap = 64, count = 0, line_no = 0;
    float *out = malloc(cap * 12 * sizeof *out);
    char line[4096];
    while (fgets(line, sizeof line, f)) {
        line_no++;
        char *p = line;
        while (*p == ' ' || *p == '\t') p++;
        if (*p == '#' || *p == '\n' || *p == '\r' || *p == 0) continue;
        if (count == cap) out = realloc(out, (cap *= 2) * 12 * sizeof *out);
        for (int k = 0; k < 12; k++) {
            while (*p == ' ' || *p == '\t' || *p == ',') p++;
            char *end;
            out[count * 12 + k] = strtof(p, &end);
            if (end == p) {
                fprintf(stderr, "error: %s: line %zu: expected 12 numbers\n", path, line_no);
                exit(2);
            }
            p = end;
        }
        count++;
    }
    fclose(f);
    *n = count;
    return out;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void usage(void) {
    fprintf(stderr,
            "usage: embree_trace MESH.tris RAYS.bin [--hits HITS.bin] [--occlusion] [--packet | --stream] [--robust]\n"
            "                    [--quality low|medium|high] [--threads N] [--repeats R] [--first F --count C]\n"
            "                    [--isa ISA] [--verbose] [--serve] [--instances PLACES.csv]\n");
    exit(2);
}

int main(int argc, char **argv) {
    const char *mesh_path = NULL, *rays_path = NULL, *hits_path = NULL, *isa = NULL, *places = NULL;
    int occlusion = 0, packet = 0, stream = 0, robust = 0, serve = 0, verbose = 0;
    int threads = 1, repeats = 1;
    long long first = 0, count = -1;
    enum RTCBuildQuality quality = RTC_BUILD_QUALITY_HIGH;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--hits") && next) hits_path = argv[++i];
        else if (!strcmp(a, "--instances") && next) places = argv[++i];
        else if (!strcmp(a, "--occlusion")) occlusion = 1;
        else if (!strcmp(a, "--packet")) packet = 1;
        else if (!strcmp(a, "--stream")) stream = 1;
        else if (!strcmp(a, "--robust")) robust = 1;
        else if (!strcmp(a, "--serve")) serve = 1;
        else if (!strcmp(a, "--verbose")) verbose = 1;
        else if (!strcmp(a, "--isa") && next) isa = argv[++i];
        else if (!strcmp(a, "--threads") && next) threads = (int)number(argv[++i], 0, 4096);
        else if (!strcmp(a, "--repeats") && next) repeats = (int)number(argv[++i], 1, 1000000);
        else if (!strcmp(a, "--first") && next) first = number(argv[++i], 0, LLONG_MAX);
        else if (!strcmp(a, "--count") && next) count = number(argv[++i], 0, LLONG_MAX);
        else if (!strcmp(a, "--quality") && next) {
            const char *q = argv[++i];
            if (!strcmp(q, "low")) quality = RTC_BUILD_QUALITY_LOW;
            else if (!strcmp(q, "medium")) quality = RTC_BUILD_QUALITY_MEDIUM;
            else if (!strcmp(q, "high")) quality = RTC_BUILD_QUALITY_HIGH;
            else usage();
        } else if (a[0] == '-') usage();
        else if (!mesh_path) mesh_path = a;
        else if (!rays_path) rays_path = a;
        else usage();
    }
    if (!mesh_path || !rays_path || repeats < 1 || threads < 0 || (packet && stream)) usage();
    if (threads == 0) threads = (int)sysconf(_SC_NPROCESSORS_ONLN);

    double t_load = now();
    size_t mesh_size, rays_size;
    char *mesh = read_file(mesh_path, &mesh_size);
    if (mesh_size < 8) die(mesh_path, "not a .tris file (shorter than its header)");
    uint32_t nv, nt;
    memcpy(&nv, mesh, 4);
    memcpy(&nt, mesh + 4, 4);
    if (mesh_size != 8 + 12 * (size_t)nv + 12 * (size_t)nt)
        die(mesh_path, "size does not match its vertex and triangle counts");
    float *vertices = aligned_alloc(64, (12 * (size_t)nv + 16 + 63) / 64 * 64);
    uint32_t *indices = aligned_alloc(64, (12 * (size_t)nt + 16 + 63) / 64 * 64);
    memcpy(vertices, mesh + 8, 12 * (size_t)nv);
    memset((char *)vertices + 12 * (size_t)nv, 0, 16);
    memcpy(indices, mesh + 8 + 12 * (size_t)nv, 12 * (size_t)nt);
    free(mesh);
    for (size_t i = 0; i < 3 * (size_t)nt; i++)
        if (indices[i] >= nv) die(mesh_path, "an index names a vertex that does not exist");
    float *rays = read_file(rays_path, &rays_size);
    if (rays_size % 32) die(rays_path, "not a whole number of 32-byte ray records");
    size_t nrays = rays_size / 32;
    if (count < 0) count = (long long)nrays - first;
    if ((size_t)first > nrays || (size_t)count > nrays - (size_t)first) die(rays_path, "--first/--count outside the file");
    t_load = now() - t_load;

    /* --serve --verbose: what Embree prints while it builds (its ISA, the
     * tree and the kernels it chose) goes to stderr, so that stdout carries
     * the protocol alone. */
    int protocol = -1;
    if (serve && verbose) {
        fflush(stdout);
        protocol = dup(1);
        if (protocol < 0 || dup2(2, 1) < 0) die("stdout", strerror(errno));
    }
    char config[256];
    snprintf(config, sizeof config, "threads=%d,set_affinity=0,verbose=%d%s%s", threads, verbose ? 2 : 0,
             isa ? ",isa=" : "", isa ? isa : "");
    RTCDevice device = rtcNewDevice(config);
    if (!device) die("rtcNewDevice", "failed");
    rtcSetDeviceErrorFunction(device, on_error, NULL);
    rtcSetDeviceMemoryMonitorFunction(device, monitor, NULL);

    double t_build = now();
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(scene, quality);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, quality);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices, 0, 12, nv);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices, 0, 12, nt);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene);
    if (places) {
        /* The mesh's scene, placed by one instance geometry per line. */
        size_t n;
        float *xfm = read_instances(places, &n);
        RTCScene top = rtcNewScene(device);
        rtcSetSceneFlags(top, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
        rtcSetSceneBuildQuality(top, quality);
        for (size_t k = 0; k < n; k++) {
            RTCGeometry inst = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(inst, scene);
            rtcSetGeometryTimeStepCount(inst, 1);
            rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, xfm + 12 * k);
            rtcCommitGeometry(inst);
            rtcAttachGeometryByID(top, inst, (unsigned)k);
            rtcReleaseGeometry(inst);
        }
        free(xfm);
        rtcCommitScene(top);
        rtcReleaseScene(scene);
        scene = top;
        instanced_tris = nt;
    }
    t_build = now() - t_build;

    Job job = {.scene = scene, .rays = rays};
    if (protocol >= 0) {
        fflush(stdout);
        if (dup2(protocol, 1) < 0) die("stdout", strerror(errno));
        close(protocol);
    }
    if (serve) {
        printf("ready %u %.6f %lld %lld\n", nt, t_build, (long long)atomic_load(&embree_bytes),
               (long long)atomic_load(&embree_peak));
        fflush(stdout);
        char line[256];
        while (fgets(line, sizeof line, stdin)) {
            long long f, c;
            char query[32], mode[32];
            int th;
            if (sscanf(line, "%lld %lld %31s %31s %d", &f, &c, query, mode, &th) != 5 || f < 0 || c < 0 ||
                (size_t)f > nrays || (size_t)c > nrays - (size_t)f || th < 0 ||
                (strcmp(query, "closest") && strcmp(query, "occlusion")) ||
                (strcmp(mode, "single") && strcmp(mode, "packet") && strcmp(mode, "stream"))) {
                printf("error: bad request: %s", line);
                fflush(stdout);
                continue;
            }
            job.first = (size_t)f;
            job.count = (size_t)c;
            job.occlusion = !strcmp(query, "occlusion");
            job.packet = !strcmp(mode, "packet");
            job.stream = !strcmp(mode, "stream");
            job.hits = NULL;
            double s = trace_pass(&job, th ? th : (int)sysconf(_SC_NPROCESSORS_ONLN));
            printf("%.9f %zu\n", s, (size_t)atomic_load(&job.found));
            fflush(stdout);
        }
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
        return 0;
    }

    job.first = (size_t)first;
    job.count = (size_t)count;
    job.occlusion = occlusion;
    job.packet = packet;
    job.stream = stream;
    float *hits = hits_path ? aligned_alloc(64, (16 * (size_t)nrays + 63) / 64 * 64) : NULL;
    double *times = calloc((size_t)repeats, sizeof *times);
    for (int r = 0; r < repeats; r++) {
        job.hits = r == 0 ? hits : NULL; /* indexed by ray number; the first pass's are written */
        times[r] = trace_pass(&job, threads);
    }
    qsort(times, (size_t)repeats, sizeof *times, cmp_double);
    double seconds = times[repeats / 2];
    if (hits_path) {
        FILE *f = fopen(hits_path, "wb");
        if (!f) die(hits_path, strerror(errno));
        if (fwrite(hits + 4 * job.first, 16, job.count, f) != job.count) die(hits_path, "short write");
        if (fclose(f) != 0) die(hits_path, strerror(errno));
    }
    printf("traced %zu rays (%s%s, Embree %s%s) against %u triangles: %zu %s in %.3f s = %.2f Mrays/s on %d threads "
           "(load %.2f s, BVH %.2f s, %.1f B/tri) -> %s\n",
           job.count, occlusion ? "occlusion" : "closest hit", packet ? ", packets of 8" : stream ? ", stream" : "",
           robust ? "robust" : "default", quality == RTC_BUILD_QUALITY_HIGH ? ", high quality" : "", nt,
           (size_t)atomic_load(&job.found), occlusion ? "occluded" : "hits", seconds,
           job.count / (seconds > 1e-9 ? seconds : 1e-9) / 1e6, threads, t_load, t_build,
           nt ? (double)atomic_load(&embree_bytes) / nt : 0.0, hits_path ? hits_path : "-");
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
    return 0;
}
