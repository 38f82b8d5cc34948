#!/usr/bin/env bash
# The README's two commands on a clean Debian 12 root, as a new user would run them: a minimal
# debootstrap chroot (only what `debootstrap --variant=minbase` installs: no compiler, no cmake, no
# library of ours), the committed tree copied in, then `scripts/test.sh` and `scripts/run.sh`.
# With a .deb (cpack's output) it also installs the package there and builds tests/consumer against
# /usr. Needs root and debootstrap; the mirror is the one this machine's apt already uses.
# Takes 10-20 minutes on 2 cores (everything is built from scratch). Not part of CI (.ci/run runs
# on a machine that already has the packages; this is the check that it would not need them).
# usage: scripts/fresh-machine.sh [PATH/TO/cullide_*.deb]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
deb="${1:-}"
[ "$(id -u)" -eq 0 ] || { echo "fresh-machine: needs root (debootstrap, chroot)" >&2; exit 1; }
command -v debootstrap >/dev/null || { echo "fresh-machine: needs debootstrap (apt-get install debootstrap)" >&2; exit 1; }

base="${CULLIDE_FRESH_BASE:-/var/tmp/cullide-debootstrap-bookworm}"
if [ ! -x "$base/bin/bash" ]; then
  # The first deb822 or one-line source of this machine's apt configuration.
  mirror="$(awk '/^URIs:/ {print $2; exit}' /etc/apt/sources.list.d/*.sources 2>/dev/null || true)"
  [ -n "$mirror" ] || mirror="$(awk '/^deb / {print $2; exit}' /etc/apt/sources.list 2>/dev/null || true)"
  [ -n "$mirror" ] || { echo "fresh-machine: no Debian mirror found in /etc/apt" >&2; exit 1; }
  echo "fresh-machine: debootstrap bookworm (minbase) into $base"
  debootstrap --variant=minbase bookworm "$base" "$mirror" >/dev/null
fi

# Every run starts from a copy of the untouched base root.
chroot_dir="$(mktemp -d /var/tmp/cullide-fresh.XXXXXX)"
cleanup() {
  for m in dev/pts dev proc sys; do umount "$chroot_dir/$m" 2>/dev/null || true; done
  rm -rf --one-file-system "$chroot_dir"
}
trap cleanup EXIT
cp -a "$base/." "$chroot_dir/"
cp /etc/resolv.conf "$chroot_dir/etc/resolv.conf"
mount -t proc proc "$chroot_dir/proc"
mount --bind /sys "$chroot_dir/sys"
mount --bind /dev "$chroot_dir/dev"
mount --bind /dev/pts "$chroot_dir/dev/pts"

mkdir -p "$chroot_dir/root/cullide"
git -C "$root" archive HEAD | tar -x -C "$chroot_dir/root/cullide"
echo "fresh-machine: $(git -C "$root" rev-parse --short HEAD) copied into $chroot_dir/root/cullide"
in_root() { chroot "$chroot_dir" /usr/bin/env -i HOME=/root PATH=/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 bash -c "$1"; }

start=$SECONDS
in_root 'cd /root/cullide && bash scripts/test.sh'
echo "fresh-machine: scripts/test.sh passed ($((SECONDS - start)) s)"
start=$SECONDS
in_root 'cd /root/cullide && bash scripts/run.sh --frames 2'
echo "fresh-machine: scripts/run.sh passed ($((SECONDS - start)) s)"

if [ -n "$deb" ]; then
  cp "$deb" "$chroot_dir/root/"
  name="$(basename "$deb")"
  # dpkg -i alone stops at the first unmet dependency (oneTBB); apt-get resolves it, as for any .deb.
  in_root "apt-get install -y -qq /root/$name >/dev/null && dpkg -s cullide | sed -n '1,/^Version/p'"
  in_root 'cullide --version && cullide run --frames 1 | tail -n 2'
  in_root 'rm -rf /tmp/c && cmake -S /root/cullide/tests/consumer -B /tmp/c -G Ninja >/dev/null && cmake --build /tmp/c >/dev/null && ctest --test-dir /tmp/c'
  echo "fresh-machine: the .deb installed and the consumer built against /usr"
fi
echo "fresh-machine: all passed"
