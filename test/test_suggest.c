/* host/base/suggest.c: the edit distance and the "did you mean" rule. */
#include <criterion/criterion.h>
#include <string.h>

#include "base/suggest.h"

Test(suggest, distance_counts_insertions_deletions_substitutions_and_swaps)
{
	cr_expect_eq(suggest_distance("size", "size"), 0);
	cr_expect_eq(suggest_distance("sze", "size"), 1);      /* insertion */
	cr_expect_eq(suggest_distance("sizes", "size"), 1);    /* deletion */
	cr_expect_eq(suggest_distance("sice", "size"), 1);     /* substitution */
	cr_expect_eq(suggest_distance("heigth", "height"), 1); /* swap */
	cr_expect_eq(suggest_distance("", "abc"), 3);
	cr_expect_eq(suggest_distance("kitten", "sitting"), 3);
	char long_word[SUGGEST_MAX_LENGTH + 2];
	memset(long_word, 'a', sizeof(long_word) - 1);
	long_word[sizeof(long_word) - 1] = '\0';
	cr_expect_gt(suggest_distance(long_word, "a"), 1000);
}

Test(suggest, nearest_within_two_edits_and_a_third_of_the_word)
{
	static const char *const options[] = {"size", "spp", "stats", "split", "scene"};
	static const char *const keys[] = {"center", "radius", "material"};

	cr_expect_str_eq(suggest_nearest("sze", options, 5), "size");
	cr_expect_str_eq(suggest_nearest("radus", keys, 3), "radius");
	cr_expect_str_eq(suggest_nearest("centre", keys, 3), "center");
	/* Too far, or too short for two edits. */
	static const char *const type[] = {"type"};
	cr_expect_null(suggest_nearest("nope", type, 1));
	cr_expect_null(suggest_nearest("nope", options, 5));
	cr_expect_null(suggest_nearest("x", options, 5));
	cr_expect_null(suggest_nearest("sz", options, 5));
	/* The word itself is no suggestion. */
	cr_expect_null(suggest_nearest("size", options, 1));
	/* The nearest wins, the first of equals. */
	cr_expect_str_eq(suggest_nearest("spit", options, 5), "split");
}

Test(suggest, append_keeps_the_message_and_adds_the_name)
{
	static const char *const options[] = {"size", "spp"};
	char err[128] = "unknown option --sze (see --help)";

	suggest_append(err, sizeof(err), "sze", options, 2, "--");
	cr_expect_str_eq(err, "unknown option --sze (see --help); did you mean \"--size\"?");
	suggest_append(err, sizeof(err), "zzzz", options, 2, "--");
	cr_expect_str_eq(err, "unknown option --sze (see --help); did you mean \"--size\"?");
	char small[8] = "unknown";
	suggest_append(small, sizeof(small), "sze", options, 2, "--");
	cr_expect_str_eq(small, "unknown");
}
