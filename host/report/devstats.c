#include "report/devstats.h"

void devstats_print(FILE *out, const struct device *devs, const int *ranks,
		    const struct device_work *work, int count, const char *noun)
{
	for (int k = 0; k < count; k++) {
		char rank[32] = "";
		if (ranks)
			snprintf(rank, sizeof(rank), "rank %d, ", ranks[k]);
		fprintf(out,
			"device %d: %s%d:%d %s: %d %s%s, %lld pixels, busy %.1f ms (kernels %.1f "
			"ms in %d launch%s; set-up %.1f ms)\n",
			k, rank, devs[k].platform_index, devs[k].device_index, devs[k].name,
			work[k].pieces, noun, work[k].pieces == 1 ? "" : "s", work[k].pixels,
			work[k].busy_ms, work[k].kernel_ms, work[k].launches,
			work[k].launches == 1 ? "" : "es", work[k].setup_ms);
	}
	fprintf(out, "devices: %d, device-level efficiency %.1f%% (mean busy / max busy)\n", count,
		100 * multidev_efficiency(work, count));
}

json_t *devstats_json(const struct device *devs, const int *ranks, const struct device_work *work,
		      int count, enum split split, const char *noun)
{
	json_t *list = json_array();

	for (int k = 0; k < count && list; k++) {
		char name[640];
		snprintf(name, sizeof(name), "%s (%s)", devs[k].name, devs[k].platform_name);
		json_t *entry =
			json_pack("{s:s, s:i, s:i, s:i, s:I, s:f, s:f}", "device", name, "platform",
				  devs[k].platform_index, "index", devs[k].device_index, "pieces",
				  work[k].pieces, "pixels", (json_int_t)work[k].pixels, "busy_ms",
				  work[k].busy_ms, "setup_ms", work[k].setup_ms);
		if (entry) {
			json_object_set_new(entry, "finish_ms", json_real(work[k].finish_ms));
			json_object_set_new(entry, "first_piece_ms",
					    json_real(work[k].first_piece_ms));
			json_object_set_new(entry, "last_piece_ms",
					    json_real(work[k].last_piece_ms));
			json_object_set_new(entry, "kernel_ms", json_real(work[k].kernel_ms));
			json_object_set_new(entry, "launches", json_integer(work[k].launches));
		}
		if (entry && work[k].renderers_opened) {
			json_object_set_new(entry, "renderers_opened",
					    json_integer(work[k].renderers_opened));
			json_object_set_new(entry, "open_ms", json_real(work[k].open_ms));
		}
		if (entry && ranks)
			json_object_set_new(entry, "rank", json_integer(ranks[k]));
		json_array_append_new(list, entry);
	}
	return json_pack("{s:s, s:s, s:o, s:f}", "split",
			 split_name(split), "piece", noun, "devices",
			 list, "device_efficiency", multidev_efficiency(work, count));
}
