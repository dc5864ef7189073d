#!/bin/sh
# The device test VM's second stage, in the host's tree (chroot; see tests/vm/init): udev
# (libcamera finds vimc's media device only through it), the devices the in-VM tests use,
# then pytest on tests/vm/guest. Its results (a junit XML, the exit status) go to the
# writable results folder; the devices' setup log too.
export HOME=/tmp PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
export PYTHONDONTWRITEBYTECODE=1 LANG=C.UTF-8 PYTEST_DISABLE_PLUGIN_AUTOLOAD=1
export SYSTEMD_IGNORE_CHROOT=1  # udevadm refuses to act in a chroot without it
out="$MOCAP_RESULTS"
log="$out/setup.log"
exec 2>>"$log"
step() { echo "stage2 $(cut -d" " -f1 /proc/uptime): $*" >> "$log"; "$@" >> "$log" 2>&1 || echo "stage2: FAILED $*" >> "$log"; }

step /lib/systemd/systemd-udevd --daemon
step udevadm trigger --action=add
step udevadm settle --timeout=60

step ip link add dev vcan0 type vcan
step ip link set vcan0 up

# gpio-sim: one chip of 8 lines labelled cam-trigger, line 3 named "trigger"
sim=/sys/kernel/config/gpio-sim/vm
step mkdir -p "$sim/bank0/line3"
echo 8 > "$sim/bank0/num_lines"
echo cam-trigger > "$sim/bank0/label"
echo trigger > "$sim/bank0/line3/name"
echo 1 > "$sim/live"
step udevadm settle --timeout=30
step ls -l /dev/gpiochip0 /dev/i2c-0 /dev/media0 /dev/video0

step cam -l
cd "$MOCAP_REPO" || exit 1
echo "stage2 $(cut -d" " -f1 /proc/uptime): pytest" >> "$log"
.venv/bin/python -m pytest -c tests/vm/guest/pytest.ini -p no:cacheprovider -q -rfE \
  --durations=0 --junitxml="$out/junit.xml" tests/vm/guest > "$out/pytest.log" 2>&1
status=$?
echo "$status" > "$out/status"
exit "$status"
