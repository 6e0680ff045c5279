/* rtcl-meshread FILE: the mesh import helper (mesh.h). Reads FILE with the
 * Open Asset Import Library and sends the triangles, or the importer's reason
 * for refusing the file, to standard output in the form mesh_import reads.
 * rtcl starts it for each mesh file of a scene; it is not meant to be run by
 * hand (its output is binary). Exit status 0 when the answer went out. */
#include <stdio.h>
#include <unistd.h>
#ifdef __linux__
#include <signal.h>
#include <sys/prctl.h>
#endif

#include "mesh.h"

int main(int argc, char **argv)
{
	struct mesh_data mesh;
	char reason[1024] = "";
	int sent;

#ifdef __linux__
	/* Ends with rtcl (killed, timed out): never left behind in a loop of
	 * the importer's. */
	prctl(PR_SET_PDEATHSIG, SIGKILL);
#endif
	if (argc != 2 || isatty(STDOUT_FILENO)) {
		fprintf(stderr, "usage: %s FILE > PIPE (rtcl's mesh import helper; rtcl runs it)\n",
			argv[0]);
		return 2;
	}
	if (mesh_import_here(argv[1], &mesh, reason, sizeof(reason)))
		sent = mesh_send(STDOUT_FILENO, NULL,
				 reason[0] ? reason : "the importer refused it");
	else {
		sent = mesh_send(STDOUT_FILENO, &mesh, NULL);
		mesh_data_free(&mesh);
	}
	/* _exit, not exit: Assimp 5.2 leaks on some error paths for malformed
	 * PLY files (found by the mesh fuzzer), and LeakSanitizer's check at exit
	 * in a sanitizer build would fail the import for memory that is not
	 * rtcl's; the process ends here, which frees it all. */
	fflush(stderr);
	_exit(sent ? 1 : 0);
}
