/* kinengine.kinematics.chainkernel: the batch chain of kinengine/kinematics/chain.py in C (optional).
 *
 *   Kernel(dof, program)     a compiled chain (kinengine/kinematics/compiler.py's program() gives the bytes)
 *   kernel.run(Q, T, J, reference)
 *                            T[i] = T_IF(Q[i]) (4, 4) [m] and J[i] = J(Q[i]) (6, dof), rows [linear;
 *                            angular], reference 0 "local_world_aligned", 1 "world", 2 "local"; T or J may
 *                            be None. Any strides that are multiples of 8 on 8-byte aligned data (the caller
 *                            copies other layouts); the GIL is released while it runs.
 *   kernel.candidates(Q, row, T, base, table, out, shifts, has_ref, within, skip, accept, same, turn_tol)
 *                            a closed-form IK solver's raw answers Q (M, n) of poses T (N, 4, 4), sorted by pose
 *                            (row (M,) int64, or None for one pose), into the joint ranges and checked (kinengine/control/
 *                            ik_candidates.py, whose numpy twin it is): per candidate the angles wrapped into
 *                            (-pi, pi] (wrapped), each joint's 2 pi shift into its range nearest the reference
 *                            (base's row if has_ref, else 0; shifts (M, n, 3) k_min, k_max, k_best unless None),
 *                            the full row (base's other coordinates), the frame's pose at it against its target;
 *                            out (M, dof + n + 4) = (full row, wrapped, kept, within the limits, position error
 *                            [m], rotation error |C - C_d|_F / sqrt 2 [rad]); kept: both errors <= accept, within
 *                            the limits unless not within, no earlier kept candidate of its pose equal to same
 *                            modulo 2 pi; skip: a candidate outside the limits is not checked (errors inf).
 *                            table (n, 4): per joint its column in q, kind (0 continuous, 1 a range
 *                            within (-pi, pi], 2 any other), lower, upper.
 *   sin_check(angles)        the kernel's sin_cos on a buffer of float64 angles (sines, then cosines): checked
 *                            against libm at import (kinengine/kinematics/compiler.py), which falls back to the
 *                            numpy chain with one warning if they differ. Building with -ffast-math is an error.
 *
 * Declared free-threading safe (Py_mod_gil): a Kernel is immutable after construction and run() writes only
 * the outputs its caller passes.
 *
 * Same algorithm as the numpy chain, over blocks of 64 configurations at a time, so nothing but the outputs and
 * a block's scratch (some tens of kB per call) is written: for each movable joint i from the root,
 *
 *     p_i = p_parent + S_parent t_i,   S_i = S_parent K_i Rz(theta_i)    (+ S_i e_z theta_i if prismatic)
 *
 * with theta_i = scaling_i q[coordinate_i] + offset_i, the joint's axis z_i = S_i e_z; then
 * C_IF = S_last R_f and p_f = p_last + S_last t_f. Jacobian column of joint i (LOCAL_WORLD_ALIGNED):
 * revolute [z_i x (p_f - p_i); z_i], prismatic [z_i; 0]; WORLD: p_i x z_i for the revolute linear part;
 * LOCAL: C_IF^T applied to both halves; a mimic joint adds scaling_i x its column to the leader's.
 * sin and cos of a block's angles are computed first, in a loop without branches that the compiler vectorizes
 * (sin_cos below: within 1.1e-16 of libm); then each step runs over the block's configurations side by side
 * (run_block), which the compiler vectorizes too. A run() whose outputs take 4 MiB or more (a batch is split
 * into one run() per thread) writes them with non-temporal stores on x86-64 (store_row). Results agree with
 * Pinocchio to rounding (about 1e-15), as the numpy chain's do.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#if defined(__FAST_MATH__)
/* -ffast-math (or -Ofast) lets the compiler reassociate sin_cos's argument reduction: measured sin/cos off by
 * up to 0.707, wrong poses with no error. Build without it (kinengine then also checks sin_cos at import). */
#error "kinengine/kinematics/chainkernel.c must not be built with -ffast-math: its sin and cos would be wrong"
#endif

/* C99 restrict where the compiler has it: MSVC spells it __restrict in C mode, C89 compilers lack it. */
#if defined(_MSC_VER)
#define KE_RESTRICT __restrict
#elif defined(__STDC_VERSION__) && __STDC_VERSION__ >= 199901L
#define KE_RESTRICT restrict
#else
#define KE_RESTRICT
#endif

#define STEP_DOUBLES 17 /* prismatic, coordinate, scaling, offset, accumulate, K (3x3 row-major), t (3) */
#define TAIL_DOUBLES 12 /* R_f (3x3 row-major), t_f (3) */

typedef struct {
    int prismatic, accumulate, plain;
    Py_ssize_t coordinate;
    double scaling, offset, K[9], t[3];
} Step;

typedef struct {
    PyObject_HEAD
    Py_ssize_t dof, m;
    Step *steps;
    unsigned char *used; /* dof flags: some step writes this Jacobian column */
    double R[9], t[3];
} Kernel;

static void
kernel_dealloc(Kernel *self)
{
    PyMem_Free(self->steps);
    PyMem_Free(self->used);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *
kernel_new(PyTypeObject *type, PyObject *args, PyObject *kwds)
{
    static char *keywords[] = {"dof", "program", NULL};
    Py_ssize_t dof;
    Py_buffer program;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "ny*", keywords, &dof, &program)) {
        return NULL;
    }
    Kernel *self = NULL;
    const double *d = (const double *)program.buf;
    Py_ssize_t count = program.len / (Py_ssize_t)sizeof(double);
    if (dof < 0 || program.len % (Py_ssize_t)sizeof(double) || count < 1 + TAIL_DOUBLES) {
        PyErr_SetString(PyExc_ValueError, "Kernel: a program of 1 + 17 m + 12 float64 values is needed");
        goto done;
    }
    double steps = d[0];
    if (!(steps >= 0 && steps == floor(steps) && steps <= (double)(count - 1 - TAIL_DOUBLES) / STEP_DOUBLES &&
          count == 1 + STEP_DOUBLES * (Py_ssize_t)steps + TAIL_DOUBLES)) { /* bounded first: no overflow */
        PyErr_SetString(PyExc_ValueError, "Kernel: the program's length does not match its step count");
        goto done;
    }
    self = (Kernel *)type->tp_alloc(type, 0);
    if (self == NULL) {
        goto done;
    }
    self->dof = dof;
    self->m = (Py_ssize_t)steps;
    self->steps = PyMem_Calloc(self->m ? self->m : 1, sizeof(Step));
    self->used = PyMem_Calloc(dof ? dof : 1, 1);
    if (self->steps == NULL || self->used == NULL) {
        Py_CLEAR(self);
        PyErr_NoMemory();
        goto done;
    }
    for (Py_ssize_t i = 0; i < self->m; i++) {
        const double *s = d + 1 + STEP_DOUBLES * i;
        Step *step = &self->steps[i];
        if (!(s[1] >= 0 && s[1] < (double)dof && s[1] == floor(s[1]))) {
            Py_CLEAR(self);
            PyErr_SetString(PyExc_ValueError, "Kernel: a step's coordinate is not one of the dof columns");
            goto done;
        }
        step->prismatic = s[0] != 0.0;
        step->coordinate = (Py_ssize_t)s[1];
        step->scaling = s[2];
        step->offset = s[3];
        step->accumulate = s[4] != 0.0;
        step->plain = s[2] == 1.0 && s[3] == 0.0;
        memcpy(step->K, s + 5, sizeof step->K);
        memcpy(step->t, s + 14, sizeof step->t);
        self->used[step->coordinate] = 1;
    }
    memcpy(self->R, d + 1 + STEP_DOUBLES * self->m, sizeof self->R);
    memcpy(self->t, d + 1 + STEP_DOUBLES * self->m + 9, sizeof self->t);
done:
    PyBuffer_Release(&program);
    return (PyObject *)self;
}

/* A float64 array's buffer with the given number of dimensions (writable if asked), or -1 and an error. */
static int
get_array(PyObject *obj, Py_buffer *view, int ndim, int writable, const char *what)
{
    if (PyObject_GetBuffer(obj, view, PyBUF_STRIDES | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0)) < 0) {
        return -1;
    }
    if (view->ndim != ndim || view->itemsize != 8 || view->format == NULL || strcmp(view->format, "d") != 0) {
        PyErr_Format(PyExc_ValueError, "Kernel: %s must be a %d-dimensional float64 array", what, ndim);
        PyBuffer_Release(view);
        return -1;
    }
    int aligned = (uintptr_t)view->buf % sizeof(double) == 0;
    for (int k = 0; k < ndim; k++) {
        aligned = aligned && view->strides[k] % (Py_ssize_t)sizeof(double) == 0;
    }
    if (!aligned) { /* read as double *: the caller (kinengine/kinematics/batch.py) passes aligned copies */
        PyErr_Format(PyExc_ValueError, "Kernel: %s must be an aligned float64 array", what);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

#define AT2(v, i, r) (*(double *)((char *)(v).buf + (i) * (v).strides[0] + (r) * (v).strides[1]))
#define AT3(v, i, r, k) \
    (*(double *)((char *)(v).buf + (i) * (v).strides[0] + (r) * (v).strides[1] + (k) * (v).strides[2]))

/* sin and cos of angles in [-LIMIT, LIMIT] without a branch, so that the compiler runs several at once
 * (SIMD): FreeBSD msun's (fdlibm's) reduction x = n pi/2 + (y0 + y1), good to 85 bits for |n| < 2^20, and
 * its kernels on [-pi/4, pi/4] (error below 1 ulp); libm's sincos takes any other angle. */
#define LIMIT 1e5
static const double INVPIO2 = 6.36619772367581382433e-01, PIO2_1 = 1.57079632673412561417e+00,
                    PIO2_1T = 6.07710050650619224932e-11, ROUND = 6755399441055744.0; /* 1.5 * 2^52 */
static const double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                    S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                    S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
static const double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                    C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                    C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;

#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__) && defined(__GLIBC__) /* ifunc */
#define CLONES __attribute__((target_clones("avx2", "default")))
#else
#define CLONES
#endif

CLONES static void
sin_cos(const double *KE_RESTRICT x, double *KE_RESTRICT sin_out, double *KE_RESTRICT cos_out, Py_ssize_t count)
{
    for (Py_ssize_t i = 0; i < count; i++) {
        double a = x[i]; /* any other angle gives some number, replaced below */
        double shifted = a * INVPIO2 + ROUND; /* its low bits: n, the nearest integer, in two's complement */
        double n = shifted - ROUND;
        double r = a - n * PIO2_1, w = n * PIO2_1T;
        double y0 = r - w, y1 = (r - y0) - w;
        double z = y0 * y0, zz = z * z;
        double v = z * y0, rs = S2 + z * (S3 + z * S4) + z * zz * (S5 + z * S6);
        double s = y0 - ((z * (0.5 * y1 - v * rs) - y1) - v * S1);
        double rc = z * (C1 + z * (C2 + z * C3)) + zz * zz * (C4 + z * (C5 + z * C6));
        double hz = 0.5 * z, h = 1.0 - hz;
        double c = h + (((1.0 - h) - hz) + (z * rc - y0 * y1));
        uint64_t q, sb, cb; /* quadrant n mod 4: (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s) */
        memcpy(&q, &shifted, 8);
        memcpy(&sb, &s, 8);
        memcpy(&cb, &c, 8);
        uint64_t odd = (uint64_t)0 - (q & 1);
        uint64_t sin_bits = ((sb & ~odd) | (cb & odd)) ^ ((q & 2) << 62);
        uint64_t cos_bits = ((cb & ~odd) | (sb & odd)) ^ (((q + 1) & 2) << 62);
        memcpy(&sin_out[i], &sin_bits, 8);
        memcpy(&cos_out[i], &cos_bits, 8);
    }
    for (Py_ssize_t i = 0; i < count; i++) {
        if (!(fabs(x[i]) <= LIMIT)) {
            sin_out[i] = sin(x[i]);
            cos_out[i] = cos(x[i]);
        }
    }
}

#define BLOCK 64 /* configurations evaluated together: their angles' sin and cos, then each step */
#define SCRATCH(m) ((37 + 9 * (m)) * BLOCK) /* doubles of scratch for run_rows and candidates_rows, then J's row */
#define STREAM_FROM (4 << 20) /* bytes of output of one run() (a thread's share) stored past the caches */

#if defined(__x86_64__) || defined(_M_X64) /* SSE2 is part of x86-64 */
#include <emmintrin.h>
#define HAVE_STREAM 1
#else
#define HAVE_STREAM 0
#endif

/* Row i of an (N, rows, cols) output from the rows x cols doubles of src (row-major). With stream, and where the
 * row is contiguous and 16-byte aligned (x86-64), by non-temporal stores: an output larger than the caches is
 * written without first reading each of its cache lines, as a plain store does; the caller fences after. */
static inline void
store_row(const Py_buffer *v, Py_ssize_t i, const double *src, Py_ssize_t cols, int stream)
{
    const Py_ssize_t rows = v->shape[1], count = rows * cols;
    char *dst = (char *)v->buf + i * v->strides[0];
    if (v->strides[2] == (Py_ssize_t)sizeof(double) && v->strides[1] == cols * (Py_ssize_t)sizeof(double)) {
#if HAVE_STREAM
        if (stream && (uintptr_t)dst % 16 == 0 && count % 2 == 0) {
            for (Py_ssize_t k = 0; k < count; k += 2) {
                _mm_stream_pd((double *)dst + k, _mm_loadu_pd(src + k));
            }
            return;
        }
#endif
        memcpy(dst, src, count * sizeof(double));
        return;
    }
    for (Py_ssize_t r = 0; r < rows; r++) {
        for (Py_ssize_t c = 0; c < cols; c++) {
            *(double *)(dst + r * v->strides[1] + c * v->strides[2]) = src[r * cols + c];
        }
    }
}

/* Row r of S over a block (its entries S0, S1, S2: one value per configuration): p_r += S_r t, and X_r = S_r K
 * (row-major K) into X0, X1, X2, which may be S0, S1, S2 themselves (each configuration's entries are read
 * before they are written). */
static inline void
times_constant(const double *S0, const double *S1, const double *S2, const double *K, const double *t, double *pr,
               double *X0, double *X1, double *X2, Py_ssize_t rows)
{
    const double t0 = t[0], t1 = t[1], t2 = t[2], k0 = K[0], k1 = K[1], k2 = K[2], k3 = K[3], k4 = K[4];
    const double k5 = K[5], k6 = K[6], k7 = K[7], k8 = K[8];
    for (Py_ssize_t b = 0; b < rows; b++) {
        double a0 = S0[b], a1 = S1[b], a2 = S2[b];
        pr[b] += a0 * t0 + a1 * t1 + a2 * t2;
        X0[b] = a0 * k0 + a1 * k3 + a2 * k6;
        X1[b] = a0 * k1 + a1 * k4 + a2 * k7;
        X2[b] = a0 * k2 + a1 * k5 + a2 * k8;
    }
}

/* T[start + b] and J[start + b] for the b < rows configurations of a block, from their joint angles theta, sines
 * and cosines ([step][row], BLOCK apart); work: SCRATCH(m) + 6 dof doubles, its first (21 + 6 m) BLOCK used here
 * (and J's row at the end); stream: store T and J past the caches (store_row). Structure of arrays (an entry of every
 * configuration, then the next entry) so that the compiler runs several configurations at once (SIMD); each
 * configuration's arithmetic is the one written in the header, in that order. */
CLONES static void
run_block(const Kernel *k, Py_ssize_t start, Py_ssize_t rows, const double *theta, const double *sines,
          const double *cosines, const Py_buffer *T, const Py_buffer *J, int reference, int stream, double *work)
{
    const Py_ssize_t m = k->m;
    double *S = work; /* S[e][b]: entry e of S (3x3 row-major) */
    double *p = S + 9 * BLOCK; /* p[r][b] */
    double *col = p + 3 * BLOCK; /* C_IF [e][b]; then col[r][b], a Jacobian column */
    double *zp = col + 9 * BLOCK; /* per step j: z_j [3][b], p_j [3][b]; then column j [6][b] */
    double *jrow = work + SCRATCH(m); /* one configuration's J (6, dof) */
    for (Py_ssize_t b = 0; b < rows; b++) {
        for (int e = 0; e < 9; e++) {
            S[e * BLOCK + b] = e % 4 == 0 ? 1.0 : 0.0;
        }
        p[b] = p[BLOCK + b] = p[2 * BLOCK + b] = 0.0;
    }
    for (Py_ssize_t j = 0; j < m; j++) {
        const Step *s = &k->steps[j];
        const double *K = s->K, *t = s->t, *th = theta + j * BLOCK, *sn = sines + j * BLOCK;
        const double *cs = cosines + j * BLOCK;
        for (int r = 0; r < 3; r++) { /* row r of S and p: p += S t, S = S K, then S = S Rz(theta) or p += S e_z theta */
            double *S0 = S + 3 * r * BLOCK, *S1 = S0 + BLOCK, *S2 = S1 + BLOCK, *pr = p + r * BLOCK;
            times_constant(S0, S1, S2, K, t, pr, S0, S1, S2, rows);
            if (s->prismatic) {
                for (Py_ssize_t b = 0; b < rows; b++) {
                    pr[b] += S2[b] * th[b];
                }
            }
            else {
                for (Py_ssize_t b = 0; b < rows; b++) { /* (a, b) -> (a c + b s, b c - a s) */
                    double x = S0[b], y = S1[b];
                    S0[b] = x * cs[b] + y * sn[b];
                    S1[b] = y * cs[b] - x * sn[b];
                }
            }
        }
        double *z = zp + 6 * j * BLOCK;
        memcpy(z, S + 2 * BLOCK, rows * sizeof(double));
        memcpy(z + BLOCK, S + 5 * BLOCK, rows * sizeof(double));
        memcpy(z + 2 * BLOCK, S + 8 * BLOCK, rows * sizeof(double));
        memcpy(z + 3 * BLOCK, p, rows * sizeof(double));
        memcpy(z + 4 * BLOCK, p + BLOCK, rows * sizeof(double));
        memcpy(z + 5 * BLOCK, p + 2 * BLOCK, rows * sizeof(double));
    }
    double *C = col; /* the frame: C_IF = S R_f into col (free until the Jacobian), p_f = p + S t_f */
    const double *R = k->R, *t = k->t;
    for (int r = 0; r < 3; r++) {
        const double *S0 = S + 3 * r * BLOCK;
        double *C0 = C + 3 * r * BLOCK;
        times_constant(S0, S0 + BLOCK, S0 + 2 * BLOCK, R, t, p + r * BLOCK, C0, C0 + BLOCK, C0 + 2 * BLOCK, rows);
    }
    if (T->buf != NULL) {
        double row[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1.0};
        for (Py_ssize_t b = 0; b < rows; b++) {
            for (int r = 0; r < 3; r++) {
                row[4 * r] = C[3 * r * BLOCK + b];
                row[4 * r + 1] = C[(3 * r + 1) * BLOCK + b];
                row[4 * r + 2] = C[(3 * r + 2) * BLOCK + b];
                row[4 * r + 3] = p[r * BLOCK + b];
            }
            store_row(T, start + b, row, 4, stream);
        }
    }
    if (J->buf == NULL) {
        return;
    }
    const double *frame = S; /* LOCAL: the columns are turned by C_IF^T, copied into S (its last use is above) */
    if (reference == 2) {
        memcpy(S, C, 9 * BLOCK * sizeof(double));
    }
    for (Py_ssize_t j = 0; j < m; j++) { /* column j over the block, into zp[j] (z_j and p_j are not read again) */
        const Step *s = &k->steps[j];
        const double *z0 = zp + 6 * j * BLOCK, *z1 = z0 + BLOCK, *z2 = z1 + BLOCK;
        const double *p0 = z2 + BLOCK, *p1 = p0 + BLOCK, *p2 = p1 + BLOCK;
        double *c0 = col, *c1 = c0 + BLOCK, *c2 = c1 + BLOCK;
        double *c3 = c2 + BLOCK, *c4 = c3 + BLOCK, *c5 = c4 + BLOCK;
        if (s->prismatic) { /* [z; 0] */
            memcpy(c0, z0, rows * sizeof(double));
            memcpy(c1, z1, rows * sizeof(double));
            memcpy(c2, z2, rows * sizeof(double));
            memset(c3, 0, 3 * BLOCK * sizeof(double));
        }
        else if (reference == 1) { /* WORLD: [p_j x z; z] */
            for (Py_ssize_t b = 0; b < rows; b++) {
                c0[b] = p1[b] * z2[b] - p2[b] * z1[b];
                c1[b] = p2[b] * z0[b] - p0[b] * z2[b];
                c2[b] = p0[b] * z1[b] - p1[b] * z0[b];
            }
        }
        else { /* [z x (p_f - p_j); z] */
            for (Py_ssize_t b = 0; b < rows; b++) {
                double d0 = p[b] - p0[b], d1 = p[BLOCK + b] - p1[b], d2 = p[2 * BLOCK + b] - p2[b];
                c0[b] = z1[b] * d2 - z2[b] * d1;
                c1[b] = z2[b] * d0 - z0[b] * d2;
                c2[b] = z0[b] * d1 - z1[b] * d0;
            }
        }
        if (!s->prismatic) {
            memcpy(c3, z0, rows * sizeof(double));
            memcpy(c4, z1, rows * sizeof(double));
            memcpy(c5, z2, rows * sizeof(double));
        }
        if (reference == 2) { /* C_IF^T applied to both halves */
            for (int h = 0; h < 6; h += 3) {
                double *v0 = col + h * BLOCK, *v1 = v0 + BLOCK, *v2 = v1 + BLOCK;
                for (Py_ssize_t b = 0; b < rows; b++) {
                    double x = v0[b], y = v1[b], w = v2[b];
                    v0[b] = frame[b] * x + frame[3 * BLOCK + b] * y + frame[6 * BLOCK + b] * w;
                    v1[b] = frame[BLOCK + b] * x + frame[4 * BLOCK + b] * y + frame[7 * BLOCK + b] * w;
                    v2[b] = frame[2 * BLOCK + b] * x + frame[5 * BLOCK + b] * y + frame[8 * BLOCK + b] * w;
                }
            }
        }
        if (s->scaling != 1.0) {
            for (int r = 0; r < 6; r++) {
                for (Py_ssize_t b = 0; b < rows; b++) {
                    col[r * BLOCK + b] *= s->scaling;
                }
            }
        }
        memcpy(zp + 6 * j * BLOCK, col, 6 * BLOCK * sizeof(double));
    }
    const Py_ssize_t dof = k->dof;
    for (Py_ssize_t b = 0; b < rows; b++) { /* each configuration's J (6, dof) in jrow, then stored */
        for (Py_ssize_t c = 0; c < dof; c++) {
            if (!k->used[c]) {
                for (int r = 0; r < 6; r++) {
                    jrow[r * dof + c] = 0.0;
                }
            }
        }
        for (Py_ssize_t j = 0; j < m; j++) {
            const Step *s = &k->steps[j];
            const double *cj = zp + 6 * j * BLOCK + b;
            double *target = jrow + s->coordinate;
            for (int r = 0; r < 6; r++) {
                if (s->accumulate) {
                    target[r * dof] += cj[r * BLOCK];
                }
                else {
                    target[r * dof] = cj[r * BLOCK];
                }
            }
        }
        store_row(J, start + b, jrow, dof, stream);
    }
}

static void
run_rows(const Kernel *k, Py_ssize_t n, const Py_buffer *Q, const Py_buffer *T, const Py_buffer *J, int reference,
         double *work)
{
    const Py_ssize_t m = k->m;
    double *theta = work + (21 + 6 * m) * BLOCK, *sines = theta + BLOCK * m, *cosines = sines + BLOCK * m;
    double bytes = (double)n * sizeof(double) * ((T->buf != NULL ? 16 : 0) + (J->buf != NULL ? 6 * k->dof : 0));
    const int stream = HAVE_STREAM && bytes >= STREAM_FROM;
    for (Py_ssize_t start = 0; start < n; start += BLOCK) {
        Py_ssize_t rows = n - start < BLOCK ? n - start : BLOCK;
        for (Py_ssize_t j = 0; j < m; j++) {
            const Step *s = &k->steps[j];
            for (Py_ssize_t b = 0; b < rows; b++) {
                double q = AT2(*Q, start + b, s->coordinate);
                theta[j * BLOCK + b] = s->plain ? q : q * s->scaling + s->offset;
            }
        }
        for (Py_ssize_t j = 0; j < m; j++) {
            sin_cos(theta + j * BLOCK, sines + j * BLOCK, cosines + j * BLOCK, rows);
        }
        run_block(k, start, rows, theta, sines, cosines, T, J, reference, stream, work);
    }
#if HAVE_STREAM
    if (stream) { /* the non-temporal stores reach memory before the caller reads the outputs */
        _mm_sfence();
    }
#endif
}

static PyObject *
kernel_run(Kernel *self, PyObject *args)
{
    PyObject *q_obj, *t_obj, *j_obj;
    int reference;
    if (!PyArg_ParseTuple(args, "OOOi", &q_obj, &t_obj, &j_obj, &reference)) {
        return NULL;
    }
    if (reference < 0 || reference > 2) {
        PyErr_SetString(PyExc_ValueError, "Kernel.run: reference must be 0, 1 or 2");
        return NULL;
    }
    Py_buffer Q = {0}, T = {0}, J = {0};
    double *zp = NULL;
    PyObject *result = NULL;
    if (get_array(q_obj, &Q, 2, 0, "Q") < 0) {
        return NULL;
    }
    Py_ssize_t n = Q.shape[0];
    if (Q.shape[1] != self->dof) {
        PyErr_SetString(PyExc_ValueError, "Kernel.run: Q must have dof columns");
        goto done;
    }
    if (t_obj != Py_None) {
        if (get_array(t_obj, &T, 3, 1, "T") < 0) {
            goto done;
        }
        if (T.shape[0] != n || T.shape[1] != 4 || T.shape[2] != 4) {
            PyErr_SetString(PyExc_ValueError, "Kernel.run: T must be (N, 4, 4)");
            goto done;
        }
    }
    if (j_obj != Py_None) {
        if (get_array(j_obj, &J, 3, 1, "J") < 0) {
            goto done;
        }
        if (J.shape[0] != n || J.shape[1] != 6 || J.shape[2] != self->dof) {
            PyErr_SetString(PyExc_ValueError, "Kernel.run: J must be (N, 6, dof)");
            goto done;
        }
    }
    zp = PyMem_RawMalloc(sizeof(double) * (SCRATCH(self->m) + 6 * self->dof));
    if (zp == NULL) {
        PyErr_NoMemory();
        goto done;
    }
    Py_BEGIN_ALLOW_THREADS
    run_rows(self, n, &Q, &T, &J, reference, zp);
    Py_END_ALLOW_THREADS
    result = Py_NewRef(Py_None);
done:
    PyMem_RawFree(zp);
    PyBuffer_Release(&Q);
    if (T.obj != NULL) {
        PyBuffer_Release(&T);
    }
    if (J.obj != NULL) {
        PyBuffer_Release(&J);
    }
    return result;
}

/* A 1-dimensional int64 array's buffer (the candidates' pose indices), or -1 and an error. */
static int
get_index(PyObject *obj, Py_buffer *view)
{
    if (PyObject_GetBuffer(obj, view, PyBUF_STRIDES | PyBUF_FORMAT) < 0) {
        return -1;
    }
    const char *f = view->format;
    if (f != NULL && (*f == '@' || *f == '=' || *f == '<')) {
        f++;
    }
    if (view->ndim != 1 || view->itemsize != 8 || f == NULL || (strcmp(f, "l") != 0 && strcmp(f, "q") != 0) ||
        (uintptr_t)view->buf % 8 != 0 || view->strides[0] % 8 != 0) {
        PyErr_SetString(PyExc_ValueError, "Kernel.candidates: row must be an aligned 1-dimensional int64 array");
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

#define KE_PI 3.141592653589793
#define TWO_PI 6.283185307179586

/* One candidate of Kernel.candidates: its raw angles q (n) wrapped into (-pi, pi] (wrapped), each joint's angle
 * put into its range (written into the full row), the 2 pi shifts (k_min, k_max, k_best) per joint if shifts is
 * not NULL; returns 1 if every joint's angle fits its range. table: n rows (column, kind, lower, upper), kind
 * 0 continuous, 1 a range within (-pi, pi], 2 any other range; ref: the reference full row or NULL (shift 0). */
static int
place(Py_ssize_t n, const double *q, const double *table, const double *ref, double turn_tol, double *wrapped,
      double *full, double *shifts)
{
    int inside = 1;
    for (Py_ssize_t j = 0; j < n; j++) {
        const double *t = table + 4 * j;
        Py_ssize_t column = (Py_ssize_t)t[0];
        int kind = (int)t[1];
        double lo = t[2], hi = t[3], a = q[j];
        if (!(a > -KE_PI && a <= KE_PI)) { /* the solver's are in [-pi, pi]: then only -pi moves */
            double m = fmod(KE_PI - a, TWO_PI);
            a = KE_PI - (m < 0 ? m + TWO_PI : m);
        }
        wrapped[j] = a;
        double angle = a, k_min = 0, k_max = 0, k_best = 0;
        double r = ref != NULL ? ref[column] : 0.0;
        if (kind == 1) {
            int fits = a >= lo - turn_tol && a <= hi + turn_tol;
            inside &= fits;
            angle = fits ? fmin(fmax(a, lo), hi) : (ref != NULL ? a + TWO_PI * rint((r - a) / TWO_PI) : a);
        }
        else if (kind == 2) {
            k_min = ceil((lo - a) / TWO_PI - 1e-12);
            k_max = floor((hi - a) / TWO_PI + 1e-12);
            double k_near = ref != NULL ? rint((r - a) / TWO_PI) : 0.0;
            int fits = k_min <= k_max;
            inside &= fits;
            k_best = fits ? fmin(fmax(k_near, k_min), k_max) : k_near;
            angle = a + TWO_PI * k_best;
            if (fits) {
                angle = fmin(fmax(angle, lo), hi);
            }
        }
        full[column] = angle;
        if (shifts != NULL) {
            shifts[3 * j] = k_min, shifts[3 * j + 1] = k_max, shifts[3 * j + 2] = k_best;
        }
    }
    return inside;
}

/* 1 if the angles a and b (n, in (-pi, pi]) agree to same modulo 2 pi */
static int
same_angles(Py_ssize_t n, const double *a, const double *b, double same)
{
    for (Py_ssize_t j = 0; j < n; j++) {
        double d = fabs(a[j] - b[j]);
        if (d > same && TWO_PI - d > same) {
            return 0;
        }
    }
    return 1;
}

typedef struct {
    Py_buffer Q, row, T, base, table, out, shifts;
} CandidateViews;

/* The work of Kernel.candidates without the GIL, in blocks of BLOCK candidates as run_rows; scratch: SCRATCH(m)
 * doubles. */
static void
candidates_rows(const Kernel *k, const CandidateViews *v, int has_ref, int within, int skip, double accept,
                double same, double turn_tol, double *scratch)
{
    const Py_ssize_t M = v->Q.shape[0], n = v->Q.shape[1], dof = k->dof, m = k->m;
    const Py_ssize_t B = v->base.shape[0];
    const double *table = (const double *)v->table.buf;
    double *theta = scratch + (21 + 6 * m) * BLOCK, *sines = theta + BLOCK * m, *cosines = sines + BLOCK * m;
    double *poses = cosines + BLOCK * m, q[64];
    Py_ssize_t shape[3] = {BLOCK, 4, 4}, strides[3] = {16 * sizeof(double), 4 * sizeof(double), sizeof(double)};
    Py_buffer Tout = {0}, none = {0};
    Tout.buf = poses;
    Tout.shape = shape;
    Tout.strides = strides;
#define ROW(i) (v->row.buf == NULL ? 0 : *(const int64_t *)((const char *)v->row.buf + (i) * v->row.strides[0]))
    Py_ssize_t first = 0; /* the first candidate of the current pose */
    for (Py_ssize_t start = 0; start < M; start += BLOCK) {
        Py_ssize_t rows = M - start < BLOCK ? M - start : BLOCK;
        for (Py_ssize_t b = 0; b < rows; b++) { /* into the ranges: the full rows and their joint angles */
            Py_ssize_t i = start + b, p = ROW(i);
            double *full = &AT2(v->out, i, 0), *wrapped = &AT2(v->out, i, dof);
            for (Py_ssize_t c = 0; c < dof; c++) {
                full[c] = AT2(v->base, B == 1 ? 0 : p, c);
            }
            for (Py_ssize_t j = 0; j < n; j++) {
                q[j] = AT2(v->Q, i, j);
            }
            /* the reference of joint j is full[column_j] (base's), read by place() before it writes it */
            AT2(v->out, i, dof + n + 1) = place(n, q, table, has_ref ? full : NULL, turn_tol, wrapped, full,
                                                v->shifts.buf != NULL ? &AT3(v->shifts, i, 0, 0) : NULL);
            for (Py_ssize_t j = 0; j < m; j++) {
                const Step *s = &k->steps[j];
                double a = full[s->coordinate];
                theta[j * BLOCK + b] = s->plain ? a : a * s->scaling + s->offset;
            }
        }
        for (Py_ssize_t j = 0; j < m; j++) {
            sin_cos(theta + j * BLOCK, sines + j * BLOCK, cosines + j * BLOCK, rows);
        }
        run_block(k, 0, rows, theta, sines, cosines, &Tout, &none, 0, 0, scratch); /* every pose, some unused */
        for (Py_ssize_t b = 0; b < rows; b++) { /* the pose at each against its target; duplicates */
            Py_ssize_t i = start + b, p = ROW(i);
            if (i > 0 && p != ROW(i - 1)) {
                first = i;
            }
            double *wrapped = &AT2(v->out, i, dof), *result = &AT2(v->out, i, dof + n);
            if (skip && within && result[1] == 0.0) { /* outside the limits: no solution asked for, not checked */
                result[0] = 0.0, result[2] = INFINITY, result[3] = INFINITY;
                continue;
            }
            const double *pose = poses + 16 * b;
            double dp = 0, dr = 0;
            for (int r = 0; r < 3; r++) {
                for (int c = 0; c < 3; c++) {
                    double d = pose[4 * r + c] - AT3(v->T, p, r, c);
                    dr += d * d;
                }
                double d = pose[4 * r + 3] - AT3(v->T, p, r, 3);
                dp += d * d;
            }
            dp = sqrt(dp), dr = sqrt(0.5 * dr);
            int keep = dp <= accept && dr <= accept && (result[1] != 0.0 || !within);
            for (Py_ssize_t e = first; keep && e < i; e++) {
                if (AT2(v->out, e, dof + n) != 0.0 && same_angles(n, wrapped, &AT2(v->out, e, dof), same)) {
                    keep = 0;
                }
            }
            result[0] = keep, result[2] = dp, result[3] = dr;
        }
    }
#undef ROW
}

static PyObject *
kernel_candidates(Kernel *self, PyObject *args)
{
    PyObject *q_obj, *row_obj, *t_obj, *base_obj, *table_obj, *out_obj, *shifts_obj;
    int has_ref, within, skip;
    double accept, same, turn_tol;
    if (!PyArg_ParseTuple(args, "OOOOOOOpppddd", &q_obj, &row_obj, &t_obj, &base_obj, &table_obj, &out_obj,
                          &shifts_obj, &has_ref, &within, &skip, &accept, &same, &turn_tol)) {
        return NULL;
    }
    CandidateViews v;
    memset(&v, 0, sizeof v);
    PyObject *result = NULL;
    double *scratch = NULL;
    if (get_array(q_obj, &v.Q, 2, 0, "Q") < 0) {
        return NULL;
    }
    const Py_ssize_t M = v.Q.shape[0], n = v.Q.shape[1];
    if ((row_obj != Py_None && get_index(row_obj, &v.row) < 0) || get_array(t_obj, &v.T, 3, 0, "T") < 0 ||
        get_array(base_obj, &v.base, 2, 0, "base") < 0 || get_array(table_obj, &v.table, 2, 0, "table") < 0 ||
        get_array(out_obj, &v.out, 2, 1, "out") < 0 ||
        (shifts_obj != Py_None && get_array(shifts_obj, &v.shifts, 3, 1, "shifts") < 0)) {
        goto done;
    }
    const Py_ssize_t N = v.T.shape[0], B = v.base.shape[0];
    int ok = n <= 64 && (v.row.buf == NULL ? N == 1 : v.row.shape[0] == M) && v.T.shape[1] == 4 && v.T.shape[2] == 4 && (B == 1 || B == N) &&
             v.base.shape[1] == self->dof && v.table.shape[0] == n && v.table.shape[1] == 4 &&
             PyBuffer_IsContiguous(&v.table, 'C') && v.out.shape[0] == M && v.out.shape[1] == self->dof + n + 4 &&
             v.out.strides[1] == sizeof(double) &&
             (v.shifts.buf == NULL || (v.shifts.shape[0] == M && v.shifts.shape[1] == n && v.shifts.shape[2] == 3 &&
                                      v.shifts.strides[2] == sizeof(double) &&
                                      v.shifts.strides[1] == 3 * sizeof(double)));
    for (Py_ssize_t j = 0; ok && j < n; j++) {
        const double *t = (const double *)v.table.buf + 4 * j;
        ok = t[0] >= 0 && t[0] < (double)self->dof && t[0] == floor(t[0]) && (t[1] == 0 || t[1] == 1 || t[1] == 2);
    }
    for (Py_ssize_t i = 0; ok && v.row.buf != NULL && i < M; i++) {
        int64_t p = *(const int64_t *)((const char *)v.row.buf + i * v.row.strides[0]);
        ok = p >= 0 && p < N &&
             (i == 0 || p >= *(const int64_t *)((const char *)v.row.buf + (i - 1) * v.row.strides[0]));
    }
    if (!ok) {
        PyErr_SetString(PyExc_ValueError,
                        "Kernel.candidates: Q (M, n <= 64), row (M,) sorted indices into T (N, 4, 4), base (1 or N, "
                        "dof), table (n, 4) (column, kind 0/1/2, lower, upper), out (M, dof + n + 4) rows contiguous, "
                        "shifts None or (M, n, 3) rows contiguous");
        goto done;
    }
    scratch = PyMem_RawMalloc(sizeof(double) * (SCRATCH(self->m) + 6 * self->dof));
    if (scratch == NULL) {
        PyErr_NoMemory();
        goto done;
    }
    if (M < BLOCK) { /* a few candidates (one pose): handing the GIL over would cost more than the work */
        candidates_rows(self, &v, has_ref, within, skip, accept, same, turn_tol, scratch);
    }
    else {
        Py_BEGIN_ALLOW_THREADS
        candidates_rows(self, &v, has_ref, within, skip, accept, same, turn_tol, scratch);
        Py_END_ALLOW_THREADS
    }
    result = Py_NewRef(Py_None);
done:
    PyMem_RawFree(scratch);
    Py_buffer *views[] = {&v.Q, &v.row, &v.T, &v.base, &v.table, &v.out, &v.shifts};
    for (size_t i = 0; i < sizeof views / sizeof views[0]; i++) {
        if (views[i]->obj != NULL) {
            PyBuffer_Release(views[i]);
        }
    }
    return result;
}

static PyMethodDef kernel_methods[] = {
    {"run", (PyCFunction)kernel_run, METH_VARARGS,
     "run(Q, T, J, reference): fill T (N, 4, 4) and/or J (N, 6, dof) for Q (N, dof); None skips one."},
    {"candidates", (PyCFunction)kernel_candidates, METH_VARARGS,
     "candidates(Q, row, T, base, table, out, shifts, has_ref, within, skip, accept, same, turn_tol): closed-form IK answers into the joint ranges, checked against their poses, deduplicated."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject KernelType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "kinengine.kinematics.chainkernel.Kernel",
    .tp_basicsize = sizeof(Kernel),
    .tp_dealloc = (destructor)kernel_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "Kernel(dof, program): a compiled chain; run(Q, T, J, reference) evaluates a batch.",
    .tp_methods = kernel_methods,
    .tp_new = kernel_new,
};

/* sin_check(angles) -> bytes: sin_cos of a buffer of float64 angles, n sines then n cosines, for the import-time
 * check against libm in kinengine/kinematics/compiler.py. */
static PyObject *
sin_check(PyObject *module, PyObject *arg)
{
    Py_buffer x;
    if (PyObject_GetBuffer(arg, &x, PyBUF_SIMPLE) < 0) {
        return NULL;
    }
    Py_ssize_t n = x.len / (Py_ssize_t)sizeof(double);
    PyObject *result = NULL;
    double *angles = PyMem_Malloc(sizeof(double) * (n ? n : 1));
    PyObject *out = PyBytes_FromStringAndSize(NULL, (Py_ssize_t)sizeof(double) * 2 * n);
    if (angles == NULL || out == NULL) {
        if (angles == NULL) {
            PyErr_NoMemory();
        }
        Py_XDECREF(out);
    }
    else {
        memcpy(angles, x.buf, sizeof(double) * n); /* any alignment */
        double *values = (double *)PyBytes_AS_STRING(out);
        sin_cos(angles, values, values + n, n);
        result = out;
    }
    PyMem_Free(angles);
    PyBuffer_Release(&x);
    return result;
}

static PyMethodDef module_methods[] = {
    {"sin_check", sin_check, METH_O,
     "sin_check(angles: bytes of float64) -> bytes: the kernel's sines then cosines of the angles."},
    {NULL, NULL, 0, NULL},
};

static int
chainkernel_exec(PyObject *module)
{
    if (PyType_Ready(&KernelType) < 0) {
        return -1;
    }
    return PyModule_AddObjectRef(module, "Kernel", (PyObject *)&KernelType); /* no reference kept on failure */
}

static PyModuleDef_Slot chainkernel_slots[] = {
    {Py_mod_exec, chainkernel_exec},
#ifdef Py_mod_gil
    /* Kernel objects are immutable after construction and run() writes only its caller's outputs. */
    {Py_mod_gil, Py_MOD_GIL_NOT_USED},
#endif
    {0, NULL},
};

static struct PyModuleDef chainkernel_module = {
    PyModuleDef_HEAD_INIT,
    .m_name = "kinengine.kinematics.chainkernel",
    .m_doc = "The batch chain in C: poses and Jacobians of blocks of configurations, side by side.",
    .m_size = 0,
    .m_methods = module_methods,
    .m_slots = chainkernel_slots,
};

PyMODINIT_FUNC
PyInit_chainkernel(void)
{
    return PyModuleDef_Init(&chainkernel_module);
}
