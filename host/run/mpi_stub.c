/* mpi_mode without MPI (MPI=0): --mpi is refused with MPI_MISSING_MESSAGE
 * before any work. */
#include <stdio.h>

#include "base/version.h"
#include "run/mode.h"
#include "run/mpi_render.h"

static int refuse(struct mode_run *run, char *err, size_t err_size)
{
	run->writes = 0;
	snprintf(err, err_size, "%s", MPI_MISSING_MESSAGE);
	return EXIT_FAILED;
}

static int never(struct mode_run *run, int checked, char *err, size_t err_size)
{
	(void)run, (void)checked, (void)err, (void)err_size;
	return EXIT_FAILED;
}

const struct mode mpi_mode = {
	.name = "mpi",
	.begin = refuse,
	.render = never,
};
