/* The counts a PLY file's header declares, checked against its body before
 * the importer reads it (in the helper, rtcl-meshread; host/scene/mesh.h).
 *
 * Assimp 5.2 believes the header: a 187-byte file declaring 2,000,000,000
 * faces made it allocate 15.6 GB, and a file declaring 1000 faces that holds
 * one came back as 1000 triangles, the missing ones invented (issue 24
 * findings 5 and 11). So: the declared records must fit the file's size at
 * the fewest bytes a record can take (checked before anything is read or
 * allocated), and then the body must hold every declared record whole
 * (walked in one pass, in constant memory). */
#ifndef RTCL_PLY_CHECK_H
#define RTCL_PLY_CHECK_H

#include <stddef.h>

/* Returns 0 when the file at path is not a PLY file (its first line is not
 * "ply"), has a header this check does not understand (left to the importer),
 * or holds every record its header declares; -1 with why in reason. */
int ply_check(const char *path, char *reason, size_t reason_size);

#endif
