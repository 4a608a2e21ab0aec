/* Answers queries on a .pvs through libsightline, one line per answer, for
 * tests/c_program.rs to compare with sightline-pvs:
 *
 *   query FILE.pvs POINTS.txt TRUNCATED.pvs
 *
 * POINTS.txt holds "x y z" lines. For each point: "point I none" or
 * "point I cell C visible N ids... | seeing N ids... | secondary N ids... | can_see A B S ...",
 * then a line "errors ok" once the bad inputs (NULL pointers, a truncated file, a
 * non-UTF-8 path, a missing file, a bad cell) have each returned their error code. */
#include "sightline.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CHECK(cond)                                                                   \
    do {                                                                              \
        if (!(cond)) {                                                                \
            fprintf(stderr, "%s:%d: check failed: %s (%s)\n", __FILE__, __LINE__,    \
                    #cond, sightline_last_error_message());                           \
            exit(2);                                                                  \
        }                                                                             \
    } while (0)

typedef int32_t (*list_fn)(const SightlinePvs *, uint32_t, uint32_t *, size_t, size_t *);

/* Count then fill: ask for the length with an empty buffer, then fill. */
static uint32_t *get_list(const SightlinePvs *pvs, list_fn f, uint32_t cell, size_t *len) {
    int32_t rc = f(pvs, cell, NULL, 0, len);
    CHECK(rc == SIGHTLINE_OK || rc == SIGHTLINE_BUFFER_TOO_SMALL);
    uint32_t *buf = malloc((*len + 1) * sizeof(uint32_t));
    CHECK(buf != NULL);
    size_t again = 0;
    CHECK(f(pvs, cell, buf, *len, &again) == SIGHTLINE_OK);
    CHECK(again == *len);
    return buf;
}

static void print_list(const char *name, const uint32_t *ids, size_t len) {
    printf(" %s %zu", name, len);
    for (size_t i = 0; i < len; i++) printf(" %u", ids[i]);
}

static void bad_inputs(const char *path, const char *truncated) {
    SightlinePvs *pvs = NULL;
    uint32_t cell = 0, n = 0;
    size_t len = 0;
    int32_t seen = 0;
    CHECK(sightline_open(NULL, &pvs) == SIGHTLINE_ERR_NULL_POINTER);
    CHECK(strlen(sightline_last_error_message()) > 0);
    CHECK(sightline_open(path, NULL) == SIGHTLINE_ERR_NULL_POINTER);
    CHECK(sightline_open(truncated, &pvs) == SIGHTLINE_ERR_TRUNCATED && pvs == NULL);
    CHECK(strstr(sightline_last_error_message(), "truncated") != NULL);
    CHECK(sightline_open("/nonexistent/dir/x.pvs", &pvs) == SIGHTLINE_ERR_IO);
    CHECK(sightline_open("\xff\xfe.pvs", &pvs) == SIGHTLINE_ERR_INVALID_ARGUMENT);
    CHECK(sightline_open_bytes(NULL, 10, &pvs) == SIGHTLINE_ERR_NULL_POINTER);
    CHECK(sightline_open_bytes((const uint8_t *)"SLPVS", 5, &pvs) == SIGHTLINE_ERR_TRUNCATED);
    CHECK(sightline_open_bytes((const uint8_t *)"hello, world", 12, &pvs) == SIGHTLINE_ERR_NOT_PVS);
    CHECK(sightline_locate(NULL, 0, 0, 0, &cell) == SIGHTLINE_ERR_NULL_POINTER);
    CHECK(sightline_cell_count(NULL, &n) == SIGHTLINE_ERR_NULL_POINTER);
    CHECK(sightline_visible(NULL, 0, NULL, 0, &len) == SIGHTLINE_ERR_NULL_POINTER);
    CHECK(sightline_can_see(NULL, 0, 0, &seen) == SIGHTLINE_ERR_NULL_POINTER);
    sightline_close(NULL);

    CHECK(sightline_open(path, &pvs) == SIGHTLINE_OK && pvs != NULL);
    CHECK(strlen(sightline_last_error_message()) == 0);
    CHECK(sightline_cell_count(pvs, &n) == SIGHTLINE_OK);
    CHECK(sightline_visible(pvs, n, NULL, 0, &len) == SIGHTLINE_ERR_INVALID_ARGUMENT);
    CHECK(sightline_visible(pvs, 0, NULL, 0, NULL) == SIGHTLINE_ERR_NULL_POINTER);
    CHECK(sightline_can_see(pvs, 0, n + 5, &seen) == SIGHTLINE_ERR_INVALID_ARGUMENT);
    CHECK(sightline_can_see(pvs, 0, 0, NULL) == SIGHTLINE_ERR_NULL_POINTER);
    CHECK(sightline_locate(pvs, 0, 0, 0, NULL) == SIGHTLINE_ERR_NULL_POINTER ||
          sightline_locate(pvs, 0, 0, 0, NULL) == SIGHTLINE_NOT_FOUND);
    CHECK(sightline_locate(pvs, 1e30, 1e30, 1e30, &cell) == SIGHTLINE_NOT_FOUND);
    CHECK(sightline_cell_box(pvs, 0, NULL) == SIGHTLINE_ERR_NULL_POINTER);
    /* A buffer one id too small is refused, and says how many are needed. */
    size_t need = 0;
    uint32_t one[1];
    int32_t rc = sightline_visible(pvs, 0, one, 0, &need);
    CHECK(need == 0 ? rc == SIGHTLINE_OK : rc == SIGHTLINE_BUFFER_TOO_SMALL);
    sightline_close(pvs);
    printf("errors ok\n");
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: query FILE.pvs POINTS.txt TRUNCATED.pvs\n");
        return 1;
    }
    CHECK(sightline_abi_version() == SIGHTLINE_ABI_VERSION);
    printf("version %s abi %u\n", sightline_version(), (unsigned)SIGHTLINE_ABI_VERSION);
    SightlinePvs *pvs = NULL;
    CHECK(sightline_open(argv[1], &pvs) == SIGHTLINE_OK);
    FILE *points = fopen(argv[2], "r");
    CHECK(points != NULL);
    double x, y, z;
    int i = 0;
    uint32_t cells = 0;
    CHECK(sightline_cell_count(pvs, &cells) == SIGHTLINE_OK);
    while (fscanf(points, "%lf %lf %lf", &x, &y, &z) == 3) {
        uint32_t cell = 0;
        int32_t rc = sightline_locate(pvs, x, y, z, &cell);
        if (rc == SIGHTLINE_NOT_FOUND) {
            size_t len = 1;
            CHECK(sightline_cells_seeing_point(pvs, x, y, z, NULL, 0, &len) == SIGHTLINE_NOT_FOUND);
            CHECK(len == 0);
            printf("point %d none\n", i++);
            continue;
        }
        CHECK(rc == SIGHTLINE_OK);
        printf("point %d cell %u", i++, cell);
        size_t len = 0;
        uint32_t *ids = get_list(pvs, sightline_visible, cell, &len);
        print_list("visible", ids, len);
        free(ids);
        ids = get_list(pvs, sightline_cells_seeing, cell, &len);
        print_list("seeing", ids, len);
        free(ids);
        ids = get_list(pvs, sightline_secondary, cell, &len);
        print_list("secondary", ids, len);
        free(ids);
        ids = get_list(pvs, sightline_neighbours, cell, &len);
        print_list("neighbours", ids, len);
        free(ids);
        printf(" can_see");
        for (uint32_t b = 0; b < cells; b += 1 + cells / 16) {
            int32_t seen = -1;
            CHECK(sightline_can_see(pvs, cell, b, &seen) == SIGHTLINE_OK);
            printf(" %u:%d", b, seen);
        }
        printf("\n");
    }
    fclose(points);
    sightline_close(pvs);
    bad_inputs(argv[1], argv[3]);
    return 0;
}
