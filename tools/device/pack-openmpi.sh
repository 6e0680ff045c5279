#!/bin/bash
# Packs this machine's Open MPI (Debian 12's 4.1, as .ci/install-deps installs
# it) into DIR, relocatable, for a machine without MPI (the device machine:
# Ubuntu 24.04, no Open MPI, no network). The tree mirrors / under DIR; use it
# there with DIR/env.sh, which points Open MPI and PMIx at it (OPAL_PREFIX,
# PMIX_INSTALL_PREFIX) and keeps to shared memory (btl self,vader), so the
# network transports (verbs, libfabric, UCX, PSM), whose libraries are not
# packed, are never loaded. Usage: tools/device/pack-openmpi.sh DIR
set -euo pipefail
dir=${1:?usage: pack-openmpi.sh DIR}
packages=(libopenmpi3 openmpi-bin openmpi-common libpmix2 libhwloc15
	libevent-core-2.1-7 libevent-pthreads-2.1-7)
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
cd /  # cp --parents copies relative paths: coreutils 9.1 fails on absolute ones
for p in "${packages[@]}"; do
	dpkg -L "$p" | while read -r f; do
		case "$f" in /usr/share/doc/* | /usr/share/man/* | /usr/share/lintian/*) continue ;; esac
		if [ -L "$f" ] || [ -f "$f" ]; then cp -a --parents "${f#/}" "$dir"; fi
	done
done
# Debian points these at /etc through the alternatives system.
for f in /usr/bin/mpirun /usr/bin/mpiexec; do
	rm -f "$dir$f"; ln -s orterun "$dir$f"
done
cat > "$dir/env.sh" <<'ENV'
# Source this to use the packed Open MPI: . DIR/env.sh
_ompi=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
export OPAL_PREFIX=$_ompi/usr
export OPAL_SYSCONFDIR=$_ompi/etc/openmpi
export PMIX_INSTALL_PREFIX=$_ompi/usr/lib/x86_64-linux-gnu/pmix2
export PMIX_MCA_mca_base_component_path=$PMIX_INSTALL_PREFIX/lib/pmix
export PATH=$_ompi/usr/bin:$PATH
export LD_LIBRARY_PATH=$_ompi/usr/lib/x86_64-linux-gnu:$_ompi/usr/lib/x86_64-linux-gnu/openmpi/lib:${LD_LIBRARY_PATH:-}
export OMPI_MCA_btl=self,vader OMPI_MCA_pml=ob1 OMPI_MCA_mtl=^ofi,psm,psm2
export OMPI_MCA_osc=^ucx OMPI_MCA_mca_base_component_show_load_errors=0
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
ENV
du -sh "$dir"
