/* "Did you mean": the known name nearest to one a user mistyped, for the
 * options (cli.c), the scene's keys and its material names (scene_check.c). */
#ifndef RTCL_SUGGEST_H
#define RTCL_SUGGEST_H

#include <stddef.h>

/* Longer words get no suggestion (and cost no more). */
#define SUGGEST_MAX_LENGTH 64

/* Returns the optimal-string-alignment distance between a and b: the
 * fewest insertions, deletions, substitutions and swaps of two neighbouring
 * characters that turn one into the other ("heigth" to "height" is 1); a
 * large number when either is longer than SUGGEST_MAX_LENGTH. */
int suggest_distance(const char *a, const char *b);

/* Returns the name of names[0 .. count) nearest to word, the first of
 * equals, when it is near: one edit for words of up to 5 characters, two
 * from 6 on (at most a third of the word, at least one); else NULL ("nope"
 * is not "type"). A name equal to word is not suggested. */
const char *suggest_nearest(const char *word, const char *const *names, size_t count);

/* Appends "; did you mean "NAME"?" to the message in buf[size] when
 * suggest_nearest finds a name; prefix goes before NAME ("--" for options). */
void suggest_append(char *buf, size_t size, const char *word, const char *const *names,
		    size_t count, const char *prefix);

#endif
