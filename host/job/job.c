#include "job/job.h"

int job_open_devices(const struct job *job, struct device *devs, int *count, char *err,
		     size_t err_size)
{
	const struct device_choice *c = &job->devices;

	if (c->list_given)
		return devices_open(&c->list, c->kind, devs, count, err, err_size);
	*count = 1;
	if (device_open_kind(&devs[0], c->platform, c->device, c->kind, err, err_size) == 0)
		return 0;
	*count = 0;
	return -1;
}
