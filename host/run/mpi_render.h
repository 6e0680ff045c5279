/* Rendering across MPI ranks (--mpi, under mpirun): rank 0 hands the pieces
 * out to every rank's devices from one dispenser (dispenser.h's split, over
 * every device of every rank) and writes the outputs; the other ranks render
 * and send their pixels to rank 0. Compiled only with MPI=1 (mpi_render.c);
 * without it mpi_stub.c says how to get it.
 *
 * A device that fails on any rank stops the run: rank 0 prints which rank and
 * device, writes nothing, and every rank exits with status 1. A rank that
 * dies makes mpirun end the others (SIGTERM): rank 0 then removes its staged
 * files (interrupt.h) and says no output was written, beside mpirun's report
 * of the rank that died.
 *
 * Every rank must render the same job: at the start the ranks compare the
 * scene's digest (scene_digest()) and every setting that changes the image or
 * its pieces (run/job_digest.h); rank 0 names the first difference and every
 * rank exits with status 1. */
#ifndef RTCL_MPI_RENDER_H
#define RTCL_MPI_RENDER_H

/* The mode is mpi_mode (run/mode.h): --mpi --frames A:B renders the
 * animation over every rank's devices; --mpi alone one image in row bands
 * (schedule/tiles.h), each rank reading its devices back once and sending
 * rank 0 the bands they rendered. */

/* The message --mpi gives when rtcl was built without MPI. */
#define MPI_MISSING_MESSAGE                                                                        \
	"--mpi: rtcl was built without MPI: install Open MPI (apt-get install libopenmpi-dev "     \
	"openmpi-bin, or make deps) and rebuild with make MPI=1"

#endif
