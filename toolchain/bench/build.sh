#!/usr/bin/env bash
# Assembles the virtual hardware-in-the-loop bench in build/bench/ (docs/bench.md), from Debian
# packages and the host build (build/host) only:
#   build/bench/kernel/      vmlinuz and the CAN and configfs modules of Debian's kernel package
#   build/bench/gpio-sim/    gpio-sim (+ irq_sim) built out of tree against the same kernel's headers
#   build/bench/initramfs.cpio.gz
#                            /init (toolchain/bench/init), busybox, bash, iproute2's ip, can-utils,
#                            the project's programs, the bench driver, the scenarios, the modules
# Every step is skipped when its output exists and is newer than its inputs.
#
#   toolchain/bench/build.sh               install what is missing (apt, non-interactive), assemble
#   toolchain/bench/build.sh --no-install  assemble only; exit 77 when a package is missing (CTest
#                                          reports the bench tests as skipped)
# Needs the host build first: cmake --preset host && cmake --build --preset host
set -euo pipefail
cd "$(dirname "$0")/../.."

out=build/bench
host=build/host
install=yes
case "${1:-}" in
  "") ;;
  --no-install) install=no ;;
  *) echo "usage: toolchain/bench/build.sh [--no-install]" >&2; exit 2 ;;
esac

say() { echo "bench/build.sh: $*" >&2; }
die() { say "error: $*"; exit 1; }
missing_exit() {
  say "$*"
  say "run toolchain/bench/build.sh (without --no-install) to install and assemble the bench"
  exit 77
}
sudo_cmd=(); [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
apt_updated=no
apt_update() {
  [ "$apt_updated" = yes ] && return
  say "apt-get update"
  "${sudo_cmd[@]}" apt-get update -qq
  apt_updated=yes
}
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
# True when $1 exists and no later argument (file or folder, searched whole) is newer than it.
up_to_date() {
  local target=$1; shift
  [ -e "$target" ] || return 1
  [ -z "$(find "$@" -newer "$target" -print -quit 2>/dev/null)" ]
}

mkdir -p "$out/deb" "$out/logs"

# 1. The kernel: the ABI and version that Debian's linux-image-amd64 depends on now. Remembered in
#    build/bench/kernel/release, so a cached bench needs no apt lists (rm -rf build/bench to move on
#    to a newer kernel).
release_file=$out/kernel/release
if [ -s "$release_file" ]; then
  read -r abi kernel_version < "$release_file"
else
  [ "$install" = yes ] && apt_update
  abi=$(apt-cache depends linux-image-amd64 2>/dev/null | sed -n 's/^ *Depends: linux-image-\([0-9][^ ]*-amd64\)$/\1/p' | head -n1)
  [ -n "$abi" ] || die "apt-cache knows no linux-image-amd64 (run apt-get update)"
  kernel_version=$(apt-cache policy "linux-image-$abi" | sed -n 's/^ *Candidate: //p')
  [ -n "$kernel_version" ] && [ "$kernel_version" != "(none)" ] || die "no candidate version of linux-image-$abi"
fi
series=${abi%%.0-*}  # 6.1.0-56-amd64 -> 6.1: the linux-source package of that series
say "kernel linux-image-$abi $kernel_version"

# 2. Debian packages installed on this machine: the emulator and what goes into the image.
packages=(qemu-system-x86 busybox-static cpio bash iproute2 can-utils binutils gzip make "linux-headers-$abi")
missing=()
for p in "${packages[@]}"; do installed "$p" || missing+=("$p"); done
if ((${#missing[@]})); then
  [ "$install" = yes ] || missing_exit "missing Debian packages: ${missing[*]}"
  apt_update
  say "installing missing Debian packages: ${missing[*]}"
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" \
    > "$out/logs/apt-install.log" 2>&1 || { cat "$out/logs/apt-install.log" >&2; die "apt-get install failed for: ${missing[*]}"; }
fi

# 3. Packages used as archives, never installed: the kernel image (not this machine's kernel) and
#    the kernel source (for gpio-sim). Same version for both, so the module matches the kernel.
image_deb=$out/deb/linux-image-${abi}_${kernel_version}_amd64.deb
source_deb=$out/deb/linux-source-${series}_${kernel_version}_all.deb
for deb in "$image_deb" "$source_deb"; do
  [ -s "$deb" ] && continue
  [ "$install" = yes ] || missing_exit "not downloaded yet: $deb"
  apt_update
  name=$(basename "$deb" | cut -d_ -f1)
  say "downloading $name=$kernel_version into $out/deb"
  (cd "$out/deb" && apt-get download -q "$name=$kernel_version" 2>&1 | grep -v '^W: Download is performed unsandboxed' >&2) || true
  [ -s "$deb" ] || die "apt-get download $name=$kernel_version did not produce $deb"
done
mkdir -p "$out/kernel"
echo "$abi $kernel_version" > "$release_file.new"
cmp -s "$release_file.new" "$release_file" || mv "$release_file.new" "$release_file"
rm -f "$release_file.new"

# 4. vmlinuz and the modules, with every module they depend on ("depends=" in each module's
#    .modinfo section), in load order: dependencies first. The image has no modules.dep: /init
#    loads build/bench/kernel/modules/load-order with insmod.
wanted_modules=(configfs can-dev can can-raw vcan sja1000 kvaser_pci)
kernel_dir=$out/kernel
if up_to_date "$kernel_dir/modules/load-order" "$image_deb" "$0"; then
  say "kernel and modules: up to date"
else
  say "kernel and modules: extracting from $(basename "$image_deb")"
  unpack=$(mktemp -d "$out/unpack.XXXXXX")
  trap 'rm -rf "$unpack"' EXIT
  dpkg-deb -x "$image_deb" "$unpack"
  cp "$unpack/boot/vmlinuz-$abi" "$kernel_dir/vmlinuz"
  rm -rf "$kernel_dir/modules"
  mkdir -p "$kernel_dir/modules"
  declare -A module_file=() visited=()
  while IFS= read -r f; do
    n=${f##*/}
    n=${n%.ko}
    module_file[${n//-/_}]=$f
  done < <(find "$unpack/lib/modules/$abi" -name '*.ko')
  load_order=()
  add_module() {  # depth first: a module's dependencies go before it
    local key=${1//-/_} file dep
    [ -n "${visited[$key]:-}" ] && return
    visited[$key]=1
    file=${module_file[$key]:-}
    [ -n "$file" ] || die "module $1 is not in linux-image-$abi"
    for dep in $(objcopy -O binary --only-section=.modinfo "$file" /dev/stdout | tr '\0' '\n' |
                 sed -n 's/^depends=//p' | tr ',' ' '); do
      add_module "$dep"
    done
    cp "$file" "$kernel_dir/modules/"
    load_order+=("$(basename "$file" .ko)")
  }
  for m in "${wanted_modules[@]}"; do add_module "$m"; done
  printf '%s\n' "${load_order[@]}" > "$kernel_dir/modules/load-order"
  rm -rf "$unpack"
  trap - EXIT
  say "modules in load order: ${load_order[*]}"
fi

# 5. gpio-sim: not enabled in Debian's kernel (nor IRQ_SIM). drivers/gpio/gpio-sim.c, its private
#    header drivers/gpio/gpiolib.h and kernel/irq/irq_sim.c of the same kernel's source become one
#    out-of-tree module. irq_sim.c calls irq_to_desc(), which the kernel does not export, once:
#    generic_handle_irq() does the same from outside the core. Load after configfs.
gpio_dir=$out/gpio-sim
gpio_ko=$gpio_dir/gpio-sim-bench.ko
headers=/usr/src/linux-headers-$abi
if up_to_date "$gpio_ko" "$source_deb" "$0"; then
  say "gpio-sim module: up to date"
else
  say "gpio-sim module: extracting the sources from $(basename "$source_deb") (reads the whole tarball)"
  rm -rf "$gpio_dir"
  mkdir -p "$gpio_dir/src"
  tree=linux-source-$series
  dpkg-deb --fsys-tarfile "$source_deb" | tar -xO "./usr/src/$tree.tar.xz" |
    tar -xJ -C "$gpio_dir/src" "$tree/drivers/gpio/gpio-sim.c" "$tree/drivers/gpio/gpiolib.h" "$tree/kernel/irq/irq_sim.c"
  cp "$gpio_dir/src/$tree/drivers/gpio/gpio-sim.c" "$gpio_dir/src/$tree/drivers/gpio/gpiolib.h" \
     "$gpio_dir/src/$tree/kernel/irq/irq_sim.c" "$gpio_dir/"
  sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' "$gpio_dir/irq_sim.c"
  ! grep -q irq_to_desc "$gpio_dir/irq_sim.c" || die "irq_sim.c of $tree still calls irq_to_desc: update the substitution in $0"
  printf '%s\n' "obj-m := gpio-sim-bench.o" "gpio-sim-bench-y := gpio-sim.o irq_sim.o" > "$gpio_dir/Kbuild"
  say "gpio-sim module: building against $headers"
  make -C "$headers" M="$PWD/$gpio_dir" modules > "$gpio_dir/build.log" 2>&1 \
    || { cat "$gpio_dir/build.log" >&2; die "gpio-sim module build failed (log above)"; }
  grep -i 'warning\|error' "$gpio_dir/build.log" | grep -v 'Skipping BTF' >&2 || true
  [ -s "$gpio_ko" ] || die "the gpio-sim build made no $gpio_ko"
fi

# 6. The initramfs. Programs are copied with the shared libraries ldd names, at the same paths, so
#    the image's dynamic loader finds them; the project's programs are stripped.
programs=(
  "$host/firmware/gyrochard"
  "$host/host_tools/gyrochar-decode"
  "$host/host_tools/gyrochar-analyze"
  "$host/host_tools/gyrochar-sim"
  "$host/tests/bench/gyrochar-bench"
)
preload=$host/tests/bench/malloc_count.so  # the allocation counter of the gyrochard-rss scenario
for p in "${programs[@]}" "$preload"; do
  [ -x "$p" ] || die "$p is missing: build the host programs first (cmake --preset host && cmake --build --preset host)"
done
system_programs=(/usr/bin/bash "$(command -v ip)" /usr/bin/candump /usr/bin/cansend /usr/bin/cangen)
busybox=/bin/busybox
for p in "${system_programs[@]}" "$busybox"; do [ -x "$p" ] || die "$p is missing (Debian packages above)"; done
ldd "$busybox" > /dev/null 2>&1 && die "$busybox is dynamically linked: the image needs busybox-static's"

initramfs=$out/initramfs.cpio.gz
inputs=("${programs[@]}" "$preload" "${system_programs[@]}" "$busybox" toolchain/bench/init tests/bench/lib.sh
        tests/bench/scenarios "$kernel_dir/modules" "$gpio_ko" "$0")
if up_to_date "$initramfs" "${inputs[@]}"; then
  say "initramfs: up to date"
else
  say "initramfs: assembling"
  root=$out/rootfs
  rm -rf "$root"
  # Debian's merged /usr: /bin, /sbin, /lib and /lib64 are links into /usr, so every program and
  # library path that ldd and the scripts use resolves as on the host.
  mkdir -p "$root"/{usr/bin,usr/sbin,usr/lib/modules,usr/lib64,proc,sys,dev,tmp,run,etc,bench/scenarios}
  for d in bin sbin lib lib64; do ln -s "usr/$d" "$root/$d"; done
  copy_with_libraries() {  # program, destination inside the image
    local program=$1 dest=$2 lib
    cp "$program" "$root$dest"
    for lib in $(ldd "$program" | sed -n 's/.*=> \(\/[^ ]*\) .*/\1/p; s/^[[:space:]]*\(\/[^ ]*\) (.*/\1/p'); do
      [ -e "$root$lib" ] && continue
      mkdir -p "$root$(dirname "$lib")"
      cp -L "$lib" "$root$lib"
    done
  }
  for p in "${programs[@]}"; do
    copy_with_libraries "$p" "/usr/bin/$(basename "$p")"
    strip --strip-unneeded "$root/usr/bin/$(basename "$p")"
  done
  for p in "${system_programs[@]}"; do copy_with_libraries "$p" "$p"; done
  copy_with_libraries "$preload" /usr/lib/malloc_count.so
  cp "$busybox" "$root/bin/busybox"
  # busybox for every command the programs above do not provide, except init: without a working
  # /init the kernel must panic (and QEMU stop at once), not fall back to busybox's init.
  for applet in $("$busybox" --list); do
    case "$applet" in init | linuxrc) continue ;; esac
    [ -e "$root/usr/bin/$applet" ] || [ -e "$root/usr/sbin/$applet" ] || ln -s busybox "$root/usr/bin/$applet"
  done
  cp "$kernel_dir"/modules/*.ko "$gpio_ko" "$root/lib/modules/"
  { cat "$kernel_dir/modules/load-order"; echo gpio-sim-bench; } > "$root/lib/modules/load-order"
  cp toolchain/bench/init "$root/init"
  cp tests/bench/lib.sh "$root/bench/"
  cp tests/bench/scenarios/*.sh "$root/bench/scenarios/"
  chmod +x "$root/init"
  (cd "$root" && find . -print0 | LC_ALL=C sort -z | cpio --null -o -H newc -R 0:0 --quiet) | gzip -6 > "$initramfs.part"
  mv "$initramfs.part" "$initramfs"
  say "initramfs: $(du -h "$initramfs" | cut -f1) compressed, $(du -sh "$root" | cut -f1) unpacked"
fi
say "ready: $kernel_dir/vmlinuz, $initramfs (run a scenario: toolchain/bench/run.sh NAME)"
