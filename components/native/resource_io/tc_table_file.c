/* tc_table_read: the friction table resource, an array file (tc_arrays.h) that the Python side converts from the
 * table's .npz (components/stripdraw/table.py, write_table_resource; the FMU build writes it into resources/).
 *
 * Entries used: the axes pressure, velocity, beta (1-D), mu (nP, nv, nb), the areas contact_area, particle_area,
 * contact_area_std, particle_area_std (all four or none: format version 2 of the table), simulated and
 * particle_area_clusters (both or none: version 3), the scalar beta_threshold, the texts content_hash and
 * provenance, and the scalar format_version (4: the version 3 arrays interpolated monotone cubic, tc_table.h;
 * without it the version is that of the arrays, 1 to 3, as written before version 4 existed). Other entries are
 * ignored. The values are checked as tc_table_from_arrays checks them (increasing finite axes, finite values >= 0,
 * the threshold in (0, 1]); a format version this reader does not know is refused.
 *
 * A path ending in ".npz" names the table whose resource is the same path ending in ".tca" (so the FMU parameter
 * table_file may name the table as the Python side does). The resource records the SHA-256 of the bytes of the
 * .npz it was made from (the text source_sha256); when the named .npz exists, its SHA-256 must be that one, so that
 * a table replaced after its resource was written is refused instead of served from the old resource. A .npz that
 * does not exist (an FMU's resources/ carry the resource form alone) is not checked; a .tca named as such neither.
 */
#include "tc_table_file.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tc_arrays.h"
#include "tc_sha256.h"

static const char *const AREAS[4] = {"contact_area", "particle_area", "contact_area_std", "particle_area_std"};

static int shape_is(const tc_array_entry *e, int ndim, const uint64_t *shape) {
    if (e->ndim != ndim) return 0;
    for (int d = 0; d < ndim; ++d)
        if (e->shape[d] != shape[d]) return 0;
    return 1;
}

static int from_arrays(const tc_arrays *a, const char *path, tc_table **out, tc_msg msg) {
    static const char *const axes[3] = {"pressure", "velocity", "beta"};
    const tc_array_entry *ax[3], *mu = tc_arrays_find(a, "mu"), *bt = tc_arrays_find(a, "beta_threshold");
    uint64_t shape[3];
    for (int k = 0; k < 3; ++k) {
        ax[k] = tc_arrays_find(a, axes[k]);
        if (ax[k] == NULL || ax[k]->kind != TC_ARRAY_FLOAT64 || ax[k]->ndim != 1 || ax[k]->count < 1)
            return tc_fail(msg, TC_ERROR, "friction table %s is malformed: it has no non-empty 1-D array '%s'", path,
                           axes[k]);
        shape[k] = ax[k]->shape[0];
    }
    if (mu == NULL || mu->kind != TC_ARRAY_FLOAT64 || !shape_is(mu, 3, shape))
        return tc_fail(msg, TC_ERROR, "friction table %s is malformed: it has no array 'mu' of shape (%llu, %llu, %llu)",
                       path, (unsigned long long)shape[0], (unsigned long long)shape[1], (unsigned long long)shape[2]);
    if (bt == NULL || bt->kind != TC_ARRAY_FLOAT64 || bt->count != 1)
        return tc_fail(msg, TC_ERROR, "friction table %s is malformed: it has no scalar 'beta_threshold'", path);
    const tc_array_entry *areas[4];
    int n_areas = 0;
    for (int k = 0; k < 4; ++k) {
        areas[k] = tc_arrays_find(a, AREAS[k]);
        if (areas[k] == NULL) continue;
        if (areas[k]->kind != TC_ARRAY_FLOAT64 || !shape_is(areas[k], 3, shape))
            return tc_fail(msg, TC_ERROR, "friction table %s is malformed: '%s' is not an array of the shape of mu",
                           path, AREAS[k]);
        ++n_areas;
    }
    if (n_areas != 0 && n_areas != 4)
        return tc_fail(msg, TC_ERROR, "friction table %s is malformed: it has %d of the 4 area arrays", path, n_areas);
    const tc_array_entry *extras[2] = {tc_arrays_find(a, "simulated"), tc_arrays_find(a, "particle_area_clusters")};
    int n_extras = 0;
    for (int k = 0; k < 2; ++k) {
        if (extras[k] == NULL) continue;
        if (extras[k]->kind != TC_ARRAY_FLOAT64 || !shape_is(extras[k], 3, shape))
            return tc_fail(msg, TC_ERROR, "friction table %s is malformed: '%s' is not an array of the shape of mu",
                           path, k == 0 ? "simulated" : "particle_area_clusters");
        ++n_extras;
    }
    if (n_extras == 1 || (n_extras == 2 && n_areas != 4))
        return tc_fail(msg, TC_ERROR, "friction table %s is malformed: version 3 needs simulated, "
                       "particle_area_clusters and the 4 area arrays", path);
    const tc_array_entry *fv = tc_arrays_find(a, "format_version");
    double version = 0.0; /* 0: not given */
    if (fv != NULL) {
        if (fv->kind != TC_ARRAY_FLOAT64 || fv->count != 1)
            return tc_fail(msg, TC_ERROR, "friction table %s is malformed: 'format_version' is not a scalar", path);
        version = fv->values[0];
        if (!(version == 1.0 || version == 2.0 || version == 3.0 || version == 4.0))
            return tc_fail(msg, TC_ERROR, "friction table %s has format version %g; this reader takes versions 1 to 4 "
                           "(a newer tribocosim wrote it: read it with that version)", path, version);
        const double held = n_extras == 2 ? 3.0 : n_areas == 4 ? 2.0 : 1.0;
        if (version != held && !(version == 4.0 && held == 3.0))
            return tc_fail(msg, TC_ERROR, "friction table %s is malformed: it says format version %g and holds the "
                           "arrays of version %g", path, version, held);
    }
    char detail[300];
    tc_msg d = {detail, sizeof detail};
    tc_table *t = NULL;
    int rc = tc_table_from_arrays(ax[0]->count, ax[1]->count, ax[2]->count, ax[0]->values, ax[1]->values,
                                  ax[2]->values, mu->values, bt->values[0], &t, d);
    if (rc == TC_OK && n_areas == 4)
        rc = tc_table_set_areas(t, areas[0]->values, areas[1]->values, areas[2]->values, areas[3]->values, d);
    if (rc == TC_OK && n_extras == 2) rc = tc_table_set_extras(t, extras[0]->values, extras[1]->values, d);
    if (rc == TC_OK && version == 4.0) rc = tc_table_set_cubic(t, d);
    if (rc != TC_OK) {
        tc_table_free(t);
        return tc_fail(msg, rc, "friction table %s is malformed: %s", path, detail);
    }
    const tc_array_entry *hash = tc_arrays_find(a, "content_hash"), *prov = tc_arrays_find(a, "provenance");
    snprintf(t->content_hash, sizeof t->content_hash, "%s", hash != NULL && hash->kind == TC_ARRAY_TEXT ? hash->text : "");
    snprintf(t->provenance, sizeof t->provenance, "%s", prov != NULL && prov->kind == TC_ARRAY_TEXT ? prov->text : "unknown");
    *out = t;
    return TC_OK;
}

/* whether path ends in suffix */
static int ends_with(const char *path, const char *suffix) {
    const size_t n = strlen(path), k = strlen(suffix);
    return n >= k && strcmp(path + n - k, suffix) == 0;
}

void tc_table_resource_path(const char *path, char *out, size_t size) {
    if (size == 0) return;
    snprintf(out, size, "%s", path);
    const size_t n = strlen(out);
    if (ends_with(path, ".npz") && n == strlen(path)) memcpy(out + n - 4, ".tca", 4);
}

/* TC_ERROR unless the resource a (read from file) was made from the bytes of the table npz, when npz exists */
static int check_source(const tc_arrays *a, const char *npz, const char *file, tc_msg msg) {
    FILE *f = fopen(npz, "rb");
    if (f == NULL) return TC_OK; /* no source beside the resource (an FMU's resources/): nothing to compare */
    fclose(f);
    char actual[65];
    int rc = tc_sha256_file(npz, actual, msg);
    if (rc != TC_OK) return rc;
    const tc_array_entry *recorded = tc_arrays_find(a, "source_sha256");
    if (recorded == NULL || recorded->kind != TC_ARRAY_TEXT)
        return tc_fail(msg, TC_ERROR, "friction table %s: its resource form %s does not record which table it was "
                       "made from, so it cannot be checked against it; rewrite it with: tribocosim fmu "
                       "table-resource %s", npz, file, npz);
    if (strcmp(recorded->text, actual) != 0)
        return tc_fail(msg, TC_ERROR, "friction table %s has changed since its resource form %s was written (the "
                       "resource was made from a file with SHA-256 %.16s..., the table now has %.16s...); rewrite "
                       "it with: tribocosim fmu table-resource %s", npz, file, recorded->text, actual, npz);
    return TC_OK;
}

int tc_table_read(const char *path, tc_table **out, tc_msg msg) {
    if (out == NULL) return tc_fail(msg, TC_ERROR, "tc_table_read needs somewhere to put the table");
    *out = NULL;
    if (path == NULL) return tc_fail(msg, TC_ERROR, "no friction table path given");
    const size_t len = strlen(path);
    char *file = malloc(len + 1);
    if (file == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the table path");
    tc_table_resource_path(path, file, len + 1);
    tc_arrays *a = NULL;
    int rc = tc_arrays_read(file, "friction table", &a, msg);
    if (rc == TC_OK && strcmp(file, path) != 0) rc = check_source(a, path, file, msg);
    if (rc == TC_OK) rc = from_arrays(a, file, out, msg);
    else if (rc == TC_ERROR && a == NULL && strcmp(file, path) != 0)
        rc = tc_fail(msg, TC_ERROR, "friction table %s: the native model reads its resource form %s, which cannot be "
                     "read (write it with: tribocosim fmu table-resource %s)", path, file, path);
    tc_arrays_free(a);
    free(file);
    return rc;
}
