/* Which piece a device takes next, for a job of `pieces` pieces over
 * `devices` devices. With the dynamic split each take gets the next piece not
 * yet handed out, so a slower device, asking less often, takes fewer (the
 * paper's dynamic scheme one level up); with the static split device k of n
 * gets the pieces [k*pieces/n, (k+1)*pieces/n) in order, whatever its speed.
 *
 * One dispenser serves the threads of one process (multidev.c) and, under
 * --mpi, every device of every rank from rank 0 (mpi_render.c). Not
 * thread-safe: both callers already hold a lock over the job's failure flag
 * when they take, so the dispenser takes none of its own. */
#ifndef RTCL_DISPENSER_H
#define RTCL_DISPENSER_H

/* SPLIT_SAMPLES (one image over devices of this process only, tiles.h): every
 * device renders the whole image, each a range of every pixel's samples; the
 * dispenser then hands device k piece k, as SPLIT_STATIC does. */
enum split { SPLIT_DYNAMIC, SPLIT_STATIC, SPLIT_SAMPLES };

/* "dynamic", "static" or "samples". */
const char *split_name(enum split split);

struct dispenser {
	enum split split;
	int pieces, devices;
	int next;	  /* dynamic: the next piece to hand out */
	int *next_static; /* static: each device's next piece (it ends where
			     the next device's first begins) */
};

/* Returns 0, or -1 when out of host memory. dispenser_free is safe after
 * either, and on a zeroed dispenser. */
int dispenser_init(struct dispenser *d, int pieces, int devices, enum split split);

void dispenser_free(struct dispenser *d);

/* The next piece for device k (0 <= k < devices), or -1 when there is none
 * left for it. */
int dispenser_take(struct dispenser *d, int k);

/* Static split: the first piece of device k of n, for count pieces (the
 * device's pieces end where device k+1's begin). */
int dispenser_static_first(int k, int n, int count);

#endif
