/* MPI transport between two ranks: rank 1 sends `MB` megabytes to rank 0,
 * whole or in chunks, as rtcl's sums or bands travel. Prints GB/s. */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char **argv)
{
	int rank, provided;
	MPI_Init_thread(&argc, &argv, MPI_THREAD_MULTIPLE, &provided);
	MPI_Comm_rank(MPI_COMM_WORLD, &rank);
	size_t mb = argc > 1 ? (size_t)atol(argv[1]) : 128;
	size_t bytes = mb << 20;
	char *buf = malloc(bytes);
	memset(buf, rank + 1, bytes);
	size_t chunks[] = {0, 1 << 20, 4 << 20, 16 << 20};
	for (int c = 0; c < 4; c++) {
		for (int rep = 0; rep < 4; rep++) {
			size_t chunk = chunks[c] ? chunks[c] : bytes;
			int n = (int)((bytes + chunk - 1) / chunk);
			MPI_Request *req = malloc(sizeof(*req) * n);
			MPI_Barrier(MPI_COMM_WORLD);
			double t = MPI_Wtime();
			for (int i = 0; i < n; i++) {
				size_t off = (size_t)i * chunk, len = bytes - off < chunk ? bytes - off : chunk;
				if (rank == 1)
					MPI_Isend(buf + off, (int)len, MPI_BYTE, 0, i, MPI_COMM_WORLD, &req[i]);
				else
					MPI_Irecv(buf + off, (int)len, MPI_BYTE, 1, i, MPI_COMM_WORLD, &req[i]);
			}
			MPI_Waitall(n, req, MPI_STATUSES_IGNORE);
			t = MPI_Wtime() - t;
			double tmax;
			MPI_Reduce(&t, &tmax, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
			if (rank == 0)
				printf("%zu MB in %s: %.1f ms, %.2f GB/s\n", mb,
				       chunks[c] ? (c == 1 ? "1 MB chunks" : c == 2 ? "4 MB chunks" : "16 MB chunks") : "one message",
				       tmax * 1e3, bytes / tmax / 1e9);
			free(req);
		}
	}
	MPI_Finalize();
	return 0;
}
