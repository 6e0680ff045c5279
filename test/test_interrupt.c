/* The interrupt thread (host/base/interrupt.c) takes the signals a user sends,
 * SIGQUIT, SIGABRT and SIGSEGV among them (test_outputs.py sends them); a
 * real crash must still crash. */
#include <criterion/criterion.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/mman.h>

#include "base/interrupt.h"

static void start_interrupt_thread(void)
{
	char err[256];

	cr_assert_eq(interrupt_setup(0, 0, err, sizeof(err)), 0, "%s", err);
}

/* A fault in a thread that blocks SIGSEGV: the kernel ends the process with
 * the default action, as without the interrupt thread. */
Test(interrupt, a_real_segmentation_fault_still_crashes, .signal = SIGSEGV)
{
	start_interrupt_thread();
	/* A page that cannot be written (not a null pointer, which UBSan would
	 * report first under make test SAN=1). */
	volatile int *page = mmap(NULL, 4096, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
	cr_assert_neq((void *)page, MAP_FAILED);
	*page = 1;
}

Test(interrupt, abort_still_aborts, .signal = SIGABRT)
{
	start_interrupt_thread();
	abort();
}
