/* What a run did, for scripts: the --stats document and the --flops
 * sidecar, as JSON (the output plan writes them). */
#ifndef RTCL_DOCUMENT_H
#define RTCL_DOCUMENT_H

#include <jansson.h>
#include <stdio.h>

#include "job/job.h"
#include "job/record.h"

/* The --stats document: one image's, or an animation's. NULL when out of
 * memory. */
json_t *report_document(const struct job *job, const struct record *record);

/* The --flops sidecar: how the counts were launched, and the figures. NULL
 * when out of memory. */
json_t *report_flops_sidecar(const struct job *job, const struct record *record);

/* A base/files.h filler that writes the JSON document `doc` (a json_t). */
int report_fill_json(FILE *file, const void *doc);

#endif
