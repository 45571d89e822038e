// The C API from an installed gsf: size queries and argument rejection. Prints "... Ok" on success.
#include <stdalign.h>
#include <stdio.h>

#include "gsf/gsf.h"

static alignas(GSF_ALIGNMENT) unsigned char storage[1 << 16];
static alignas(GSF_ALIGNMENT) unsigned char blob[4096];

static int failures = 0;
static void expect(int got, int want, const char* what) {
  if (got != want) {
    printf("%s: %s, expected %s\n", what, gsf_status_string(got), gsf_status_string(want));
    ++failures;
  }
}

int main(void) {
  gsf_config cfg;
  gsf_config_default(&cfg);
  const size_t storage_bytes = gsf_localizer_storage_bytes(), workspace_bytes = gsf_workspace_bytes(&cfg);
  if (storage_bytes == 0 || storage_bytes > sizeof(storage) || workspace_bytes == 0) {
    printf("sizes: storage %zu workspace %zu\n", storage_bytes, workspace_bytes);
    return 1;
  }
  gsf_map map;
  expect(gsf_map_load(NULL, 0, &map), GSF_STATUS_INVALID_ARGUMENT, "NULL blob");
  expect(gsf_map_load(blob + 8, 1024, &map), GSF_STATUS_INVALID_ARGUMENT, "misaligned blob");
  expect(gsf_map_load(blob, 1024, &map), GSF_STATUS_CORRUPT_DATA, "zero blob");
  gsf_localizer* loc = NULL;
  expect(gsf_localizer_init(storage + 4, storage_bytes, &cfg, &map, blob, sizeof(blob), &loc),
         GSF_STATUS_INVALID_ARGUMENT, "misaligned storage");
  expect(gsf_localizer_init(storage, storage_bytes - 1, &cfg, &map, blob, sizeof(blob), &loc),
         GSF_STATUS_BUFFER_TOO_SMALL, "small storage");
  expect(gsf_localizer_init(storage, storage_bytes, &cfg, &map, blob, sizeof(blob), &loc), GSF_STATUS_INVALID_ARGUMENT,
         "map not loaded");
  gsf_result r;
  expect(gsf_localize(loc, NULL, 4, 0, NULL, NULL, 0, &r), GSF_STATUS_INVALID_ARGUMENT, "NULL localizer");
  expect(r.status, GSF_STATUS_INVALID_ARGUMENT, "result status");
  printf("storage %zu workspace %zu %s\n", storage_bytes, workspace_bytes,
         failures == 0 ? gsf_status_string(GSF_STATUS_OK) : "FAILED");
  return failures == 0 ? 0 : 1;
}
