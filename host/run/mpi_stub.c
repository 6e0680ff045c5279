/* mpi_render.h without MPI (MPI=0): --mpi is refused with MPI_MISSING_MESSAGE
 * before any work (main.c). */
#include "run/mpi_render.h"

#include <stdio.h>

#include "base/version.h"

int mpi_render_available(void)
{
	return 0;
}

int mpi_render_frames(struct run *run)
{
	(void)run;
	fprintf(stderr, "rtcl: %s\n", MPI_MISSING_MESSAGE);
	return EXIT_FAILED;
}

int mpi_render_image(struct run *run)
{
	return mpi_render_frames(run);
}
