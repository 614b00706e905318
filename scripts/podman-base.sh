#!/bin/sh
# scripts/podman-base.sh CONF — makes podman usable on a machine like ours, where no image
# registry can be reached and no systemd runs: writes the containers.conf CONF (runc, the
# open-files limit of this shell, netavark), and makes the base images the Dockerfiles start
# FROM out of Debian's archive when they are missing: debian:12 (debootstrap --variant=minbase
# bookworm) and debian:12-slim (the same without documentation, man pages and locales).  Both
# are kept in podman's image store, so the next run finds them.  Export CONTAINERS_CONF=CONF
# before running podman.  Needs root, podman, runc, debootstrap (make deps installs them).
set -eu
conf=${1:?usage: scripts/podman-base.sh CONTAINERS_CONF}
mkdir -p "$(dirname "$conf")"
n=$(ulimit -Hn)
cat >"$conf" <<EOF
[containers]
default_ulimits = ["nofile=$n:$n", "nproc=32768:32768"]
[engine]
runtime = "runc"
[network]
network_backend = "netavark"
EOF
export CONTAINERS_CONF="$conf"
have() { podman image exists "$1" 2>/dev/null; }
if have docker.io/library/debian:12 && have docker.io/library/debian:12-slim; then exit 0; fi
mirror=${DEBIAN_MIRROR:-http://deb.debian.org/debian}
root=$(mktemp -d /tmp/cellar-debian-XXXXXX)
trap 'rm -rf "$root"' EXIT
echo "podman-base: making debian:12 from $mirror (debootstrap, about a minute)" >&2
debootstrap --variant=minbase bookworm "$root/full" "$mirror" >"$root/log" 2>&1 ||
    { tail -n 20 "$root/log" >&2; exit 1; }
tar --numeric-owner -C "$root/full" -c . |
    podman import -q --change 'CMD ["bash"]' - localhost/debian:12 >/dev/null
podman tag localhost/debian:12 docker.io/library/debian:12
rm -rf "$root/full/usr/share/doc/"* "$root/full/usr/share/man/"* "$root/full/usr/share/info/"* \
    "$root/full/usr/share/locale/"* "$root/full/var/cache/apt/"* "$root/full/var/lib/apt/lists/"*
tar --numeric-owner -C "$root/full" -c . |
    podman import -q --change 'CMD ["bash"]' - localhost/debian:12-slim >/dev/null
podman tag localhost/debian:12-slim docker.io/library/debian:12-slim
