/* The nodal-field file of the strip: recorder, CSV writer and the field_input reader; see tc_fields.h.
 *
 * Portability: all of this is C11's standard library except creating a missing folder, for which C has no
 * function: mkdir (<sys/stat.h>, POSIX) or _mkdir (<direct.h>, Windows), and the process id in the name of
 * the temporary file, getpid (<unistd.h>) or _getpid (<process.h>), both behind #if defined(_WIN32).
 */
#if !defined(_WIN32) && !defined(_POSIX_C_SOURCE)
#define _POSIX_C_SOURCE 200809L /* mkdir, getpid */
#endif

#include "tc_fields.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <direct.h>
#include <process.h>
#else
#include <sys/stat.h>
#include <unistd.h>
#endif

#define HEADER "# tribocosim strip-draw nodal fields, format 1"
#define X_LINE "# X [m]: "
#define QUANTITIES 3 /* beta, U, contact */

static const char *const NAMES[QUANTITIES] = {"beta", "U", "contact"};

static char *copy_string(const char *s) {
    size_t n = strlen(s) + 1;
    char *c = malloc(n);
    if (c != NULL) memcpy(c, s, n);
    return c;
}

/* x with 17 significant digits and '.' as the decimal point (a C locale may have set another) */
static void put_number(FILE *f, double x) {
    char buf[40];
    snprintf(buf, sizeof buf, "%.17g", x);
    for (char *p = buf; *p; ++p)
        if (*p == ',') *p = '.';
    fputs(buf, f);
}

/* ---- writing ---------------------------------------------------------------------------------------------- */

static int is_separator(char c) {
#if defined(_WIN32)
    return c == '/' || c == '\\';
#else
    return c == '/';
#endif
}

static int make_folder(const char *folder) {
#if defined(_WIN32)
    return _mkdir(folder);
#else
    return mkdir(folder, 0777);
#endif
}

static long process_id(void) {
#if defined(_WIN32)
    return (long)_getpid();
#else
    return (long)getpid();
#endif
}

/* every folder on the way to path[0..dir_len), from the top; a failure shows when the file is opened */
static void make_parents(char *path, size_t dir_len) {
    for (size_t i = 1; i < dir_len; ++i) {
        if (!is_separator(path[i]) || is_separator(path[i - 1]) || path[i - 1] == ':') continue;
        const char c = path[i];
        path[i] = '\0';
        (void)make_folder(path);
        path[i] = c;
    }
}

struct tc_field_recorder {
    char *path;
    double interval;
    size_t m;         /* nodes per row */
    double *X;        /* m values */
    double window[2];
    char *metadata;   /* parameter lines */
    size_t n, cap;    /* rows recorded, rows allocated */
    double *time;     /* cap values */
    double *rows[QUANTITIES]; /* cap x m each, row-major */
};

static void write_csv(FILE *f, const tc_field_recorder *r) {
    fprintf(f, "%s\n%s", HEADER, X_LINE);
    for (size_t i = 0; i < r->m; ++i) {
        if (i) fputc(',', f);
        put_number(f, r->X[i]);
    }
    fputs("\n# window [m]: ", f);
    put_number(f, r->window[0]);
    fputc(',', f);
    put_number(f, r->window[1]);
    fputc('\n', f);
    for (const char *line = r->metadata; *line;) {
        const char *end = strchr(line, '\n');
        const size_t len = end != NULL ? (size_t)(end - line) : strlen(line);
        fputs("# parameter ", f);
        for (size_t k = 0; k < len; ++k) fputc((unsigned char)line[k] < 0x20 ? '?' : line[k], f);
        fputc('\n', f);
        line += len + (end != NULL);
    }
    fputs("time", f);
    for (int q = 0; q < QUANTITIES; ++q)
        for (size_t i = 0; i < r->m; ++i) fprintf(f, ",%s_%zu", NAMES[q], i);
    fputc('\n', f);
    for (size_t row = 0; row < r->n; ++row) {
        put_number(f, r->time[row]);
        for (int q = 0; q < QUANTITIES; ++q)
            for (size_t i = 0; i < r->m; ++i) {
                fputc(',', f);
                put_number(f, r->rows[q][row * r->m + i]);
            }
        fputc('\n', f);
    }
}

int tc_field_recorder_write(const tc_field_recorder *r, tc_msg msg) {
    if (r == NULL) return tc_fail(msg, TC_ERROR, "tc_field_recorder_write needs a recorder");
    const char *path = r->path;
    const size_t len = strlen(path);
    size_t dir_len = len;
    while (dir_len > 0 && !is_separator(path[dir_len - 1])) --dir_len;
    if (dir_len == len) return tc_fail(msg, TC_ERROR, "field_output = '%s' names a folder, not a file", path);
    const size_t tmp_size = len + 64;
    char *tmp = malloc(tmp_size);
    if (tmp == NULL) return tc_fail(msg, TC_NOMEM, "field_output = '%s' cannot be written: out of memory", path);
    snprintf(tmp, tmp_size, "%.*s.%s.%ld.%llx.partial", (int)dir_len, path, path + dir_len, process_id(),
             (unsigned long long)(uintptr_t)(const void *)r); /* two recorders in one process differ too */
    make_parents(tmp, dir_len);
    errno = 0;
    FILE *f = fopen(tmp, "w");
    int rc = TC_OK;
    if (f == NULL) {
        rc = tc_fail(msg, TC_ERROR, "field_output = '%s' cannot be written: %s", path, strerror(errno));
    } else {
        write_csv(f, r);
        const int failed = ferror(f);
        errno = 0;
        if (fclose(f) != 0 || failed) {
            rc = tc_fail(msg, TC_ERROR, "field_output = '%s' cannot be written: %s", path,
                         errno ? strerror(errno) : "write error");
            remove(tmp);
        }
    }
    if (rc == TC_OK) {
#if defined(_WIN32)
        remove(path); /* rename does not replace an existing file on Windows */
#endif
        errno = 0;
        if (rename(tmp, path) != 0) {
            rc = tc_fail(msg, TC_ERROR, "field_output = '%s' cannot be written: %s", path, strerror(errno));
            remove(tmp);
        }
    }
    free(tmp);
    return rc;
}

/* ---- the recorder ---------------------------------------------------------------------------------------- */

void tc_field_recorder_free(tc_field_recorder *r) {
    if (r == NULL) return;
    free(r->path);
    free(r->X);
    free(r->metadata);
    free(r->time);
    for (int k = 0; k < QUANTITIES; ++k) free(r->rows[k]);
    free(r);
}

int tc_field_recorder_create(const char *path, double interval, size_t n_nodes, const double *X,
                             const double window[2], const char *metadata, tc_field_recorder **out, tc_msg msg) {
    char buf[TC_REPR_SIZE];
    if (out == NULL) return tc_fail(msg, TC_ERROR, "tc_field_recorder_create needs somewhere to put the recorder");
    *out = NULL;
    if (!(interval >= 0) || isinf(interval))
        return tc_fail(msg, TC_ERROR, "field_output_interval = %s s must be finite and >= 0",
                       tc_repr_double(interval, buf));
    if (path == NULL || path[0] == '\0') return tc_fail(msg, TC_ERROR, "field_output: no file name given");
    if (n_nodes == 0 || X == NULL || window == NULL)
        return tc_fail(msg, TC_ERROR, "field_output needs the mesh: n_nodes >= 1 node coordinates X and the window");
    if (n_nodes > SIZE_MAX / sizeof(double) / 16)
        return tc_fail(msg, TC_ERROR, "field_output: %zu nodes are too many", n_nodes);
    tc_field_recorder *r = calloc(1, sizeof *r);
    if (r == NULL) return tc_fail(msg, TC_NOMEM, "field_output: out of memory for the recorder");
    r->path = copy_string(path);
    r->X = malloc(n_nodes * sizeof *r->X);
    r->metadata = copy_string(metadata != NULL ? metadata : "");
    if (r->path == NULL || r->X == NULL || r->metadata == NULL) {
        tc_field_recorder_free(r);
        return tc_fail(msg, TC_NOMEM, "field_output: out of memory for the recorder");
    }
    r->interval = interval;
    r->m = n_nodes;
    memcpy(r->X, X, n_nodes * sizeof *r->X);
    r->window[0] = window[0];
    r->window[1] = window[1];
    *out = r;
    return TC_OK;
}

/* room for one more row: capacity doubled (16 rows first); a failure leaves a consistent recorder */
static int grow(tc_field_recorder *r) {
    if (r->n < r->cap) return TC_OK;
    size_t cap = r->cap == 0 ? 16 : r->cap;
    if (r->cap > 0) {
        if (cap > SIZE_MAX / 2 / sizeof(double) / r->m) return TC_NOMEM;
        cap *= 2;
    }
    double *t = realloc(r->time, cap * sizeof *t);
    if (t == NULL) return TC_NOMEM;
    r->time = t;
    for (int k = 0; k < QUANTITIES; ++k) {
        double *a = realloc(r->rows[k], cap * r->m * sizeof *a);
        if (a == NULL) return TC_NOMEM;
        r->rows[k] = a;
    }
    r->cap = cap;
    return TC_OK;
}

int tc_field_recorder_record(tc_field_recorder *r, double t, const double *beta, const double *U,
                             const double *contact, int force, tc_msg msg) {
    if (r == NULL || beta == NULL || U == NULL || contact == NULL)
        return tc_fail(msg, TC_ERROR, "tc_field_recorder_record needs a recorder and the three fields");
    if (!force && r->n > 0 && t < r->time[r->n - 1] + r->interval * (1.0 - 1e-9)) return TC_OK;
    if (grow(r) != TC_OK)
        return tc_fail(msg, TC_NOMEM, "field_output: out of memory for row %zu (%zu nodes)", r->n + 1, r->m);
    const double *src[QUANTITIES] = {beta, U, contact};
    for (int k = 0; k < QUANTITIES; ++k) memcpy(r->rows[k] + r->n * r->m, src[k], r->m * sizeof(double));
    r->time[r->n++] = t;
    return TC_OK;
}

void tc_field_recorder_truncate(tc_field_recorder *r, double t) {
    if (r == NULL) return;
    while (r->n > 0 && r->time[r->n - 1] > t * (1.0 + 1e-12) + 1e-15) --r->n;
}

int tc_field_recorder_finish(tc_field_recorder *r, double t, const double *beta, const double *U,
                             const double *contact, tc_msg msg) {
    if (r == NULL) return tc_fail(msg, TC_ERROR, "tc_field_recorder_finish needs a recorder");
    if (r->n == 0 || t > r->time[r->n - 1]) {
        int rc = tc_field_recorder_record(r, t, beta, U, contact, 1, msg);
        if (rc != TC_OK) return rc;
    }
    return tc_field_recorder_write(r, msg);
}

size_t tc_field_recorder_rows(const tc_field_recorder *r) { return r != NULL ? r->n : 0; }

double tc_field_recorder_last_time(const tc_field_recorder *r) {
    return r != NULL && r->n > 0 ? r->time[r->n - 1] : NAN;
}

/* ---- the reader ---------------------------------------------------------------------------------------------- */

/* A number of the file at *s (printed by put_number, or any decimal number with '.'), independent of the C
 * locale: the digits are converted as "<digits>e<exponent>"; *s moves past it. 0 if there is none. */
static int read_number(const char **s, double *value) {
    char work[96];
    const char *p = *s;
    size_t nd = 0;
    long long n_frac = 0;
    const int neg = *p == '-';
    if (*p == '+' || *p == '-') ++p;
    int digits = 0;
    for (; *p >= '0' && *p <= '9'; ++p, ++digits) {
        if (nd < 40) work[nd++] = *p;
        else n_frac -= 1; /* a digit dropped far beyond a double's precision: one power of ten */
    }
    if (*p == '.')
        for (++p; *p >= '0' && *p <= '9'; ++p, ++digits)
            if (nd < 40) {
                work[nd++] = *p;
                ++n_frac;
            }
    if (digits == 0) return 0;
    long long exponent = 0;
    if (*p == 'e' || *p == 'E') {
        ++p;
        const int eneg = *p == '-';
        if (*p == '+' || *p == '-') ++p;
        if (!(*p >= '0' && *p <= '9')) return 0;
        for (; *p >= '0' && *p <= '9'; ++p)
            if (exponent < 100000000) exponent = exponent * 10 + (*p - '0');
        if (eneg) exponent = -exponent;
    }
    snprintf(work + nd, sizeof work - nd, "e%lld", exponent - n_frac);
    const double v = strtod(work, NULL);
    *value = neg ? -v : v;
    *s = p;
    return 1;
}

/* the whole file as a NUL-terminated text */
static char *read_text(const char *path) {
    FILE *f = fopen(path, "rb");
    if (f == NULL) return NULL;
    size_t cap = 1 << 16, used = 0;
    char *buf = malloc(cap + 1);
    while (buf != NULL) {
        used += fread(buf + used, 1, cap - used, f);
        if (ferror(f) || feof(f)) break;
        char *bigger = cap <= SIZE_MAX / 4 ? realloc(buf, 2 * cap + 1) : NULL;
        if (bigger == NULL) {
            free(buf);
            buf = NULL;
            break;
        }
        buf = bigger;
        cap *= 2;
    }
    const int failed = ferror(f);
    fclose(f);
    if (buf == NULL || failed) {
        free(buf);
        return NULL;
    }
    buf[used] = '\0';
    return buf;
}

int tc_field_read_initial_beta(const char *path, size_t n_nodes, const double *X, double *beta_out, tc_msg msg) {
    errno = 0;
    char *text = read_text(path);
    if (text == NULL)
        return tc_fail(msg, TC_ERROR, "field_input = '%s' cannot be read: %s", path,
                       errno ? strerror(errno) : "out of memory or not a file");
    int rc = TC_OK;
    double *Xf = malloc((n_nodes + 1) * sizeof *Xf), *row = malloc((3 * n_nodes + 2) * sizeof *row);
    if (Xf == NULL || row == NULL) {
        rc = tc_fail(msg, TC_NOMEM, "field_input = '%s': out of memory", path);
        goto done;
    }
    if (strncmp(text, HEADER, strlen(HEADER)) != 0) {
        rc = tc_fail(msg, TC_ERROR, "field_input = '%s' is not a field_output file (it does not start with '%s')",
                     path, HEADER);
        goto done;
    }
    /* the X line: n_nodes values */
    const char *p = strstr(text, "\n" X_LINE);
    size_t nx = 0;
    if (p != NULL) {
        p += 1 + strlen(X_LINE);
        double v;
        while (nx <= n_nodes && read_number(&p, &v)) {
            Xf[nx++] = v;
            if (*p != ',') break;
            ++p;
        }
    }
    int same = nx == n_nodes;
    for (size_t i = 0; same && i < n_nodes; ++i) same = fabs(Xf[i] - X[i]) <= 1e-12;
    if (!same) {
        rc = tc_fail(msg, TC_ERROR, "field_input = '%s' was written for another mesh (%zu nodes over [%g, %g] m; this "
                     "strip has %zu nodes over [%g, %g] m): use the same geometry and n_elements", path, nx,
                     nx ? Xf[0] : NAN, nx ? Xf[nx - 1] : NAN, n_nodes, X[0], X[n_nodes - 1]);
        goto done;
    }
    /* the last data row: time, then beta (n_nodes values) */
    size_t len = strlen(text);
    while (len > 0 && (text[len - 1] == '\n' || text[len - 1] == '\r')) text[--len] = '\0';
    const char *last = strrchr(text, '\n');
    last = last != NULL ? last + 1 : text;
    size_t nv = 0;
    double v;
    const char *q = last;
    while (nv < 3 * n_nodes + 1 && read_number(&q, &v)) {
        row[nv++] = v;
        if (*q != ',') break;
        ++q;
    }
    if (last[0] == '#' || last[0] == 't' || nv != 3 * n_nodes + 1 || *q != '\0') {
        rc = tc_fail(msg, TC_ERROR, "field_input = '%s' has no complete row of %zu nodes' fields (its last line holds "
                     "%zu numbers)", path, n_nodes, nv);
        goto done;
    }
    memcpy(beta_out, row + 1, n_nodes * sizeof *beta_out);
done:
    free(Xf);
    free(row);
    free(text);
    return rc;
}
