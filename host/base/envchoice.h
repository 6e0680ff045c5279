/* A choice among named ways read from an environment variable (the
 * measuring switches RTCL_MPI_SUMS, RTCL_FRAMES_READ). */
#ifndef RTCL_ENVCHOICE_H
#define RTCL_ENVCHOICE_H

#include <stdlib.h>
#include <string.h>

/* The index in names[0 .. count) of variable's value, unset_choice when it
 * is unset or empty, or -1 for any other value (the caller says what it
 * expected). */
static inline int env_choice(const char *variable, const char *const *names, int count,
			     int unset_choice)
{
	const char *value = getenv(variable);

	if (!value || !*value)
		return unset_choice;
	for (int i = 0; i < count; i++)
		if (strcmp(value, names[i]) == 0)
			return i;
	return -1;
}

#endif
