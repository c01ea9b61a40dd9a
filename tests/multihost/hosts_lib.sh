# Sourced by the multihost tests, inside their own `unshare -n -m`: named network namespaces standing for hosts,
# joined by veth pairs to a bridge, with an sshd on each that needs one. No address or route outside them.

# A private mount view: named namespaces in a tmpfs of this test only; an empty ~/.bashrc for the hosts' login
# shells (ssh runs `$SHELL -c`, and bash started by sshd reads ~/.bashrc: a developer machine's may take tens of
# seconds for several sessions at once, while these tests time the launcher); /run/sshd for sshd.
mh_private_view() {  # TAG
  mount --make-rprivate /
  local home; home="$(getent passwd root | cut -d: -f6)"
  [ -f "$home/.bashrc" ] && mount --bind /dev/null "$home/.bashrc"
  mkdir -p /run/netns && mount -t tmpfs "fploc-$1-netns" /run/netns
  mkdir -p /run/sshd
}

# A bridge br0 and one namespace per host, addresses 10.213.0.1, .2, ... in the order given, multicast on eth0.
mh_bridge() {  # HOST...
  ip link set lo up
  ip link add br0 type bridge mcast_snooping 0
  ip link set br0 up
  local n=1 h
  for h in "$@"; do
    ip netns add "$h"
    ip link add "v-$h" type veth peer name eth0 netns "$h"
    ip link set "v-$h" master br0 up
    ip -n "$h" link set lo up
    ip -n "$h" addr add "10.213.0.$n/24" dev eth0
    ip -n "$h" link set eth0 up multicast on
    ip -n "$h" route add 224.0.0.0/4 dev eth0
    ip netns exec "$h" sysctl -qw net.core.rmem_max=33554432 net.core.rmem_default=4194304 2>/dev/null || true
    n=$((n + 1))
  done
}

# The client key DIR/id (and DIR/authorized_keys holding it).
mh_client_key() {  # DIR COMMENT
  ssh-keygen -q -t ed25519 -N '' -f "$1/id" -C "$2"
  cp "$1/id.pub" "$1/authorized_keys"
}

# An sshd in HOST's namespace on ADDRESS (its own host key; root with DIR/id only): DIR/sshd-HOST.{conf,pid,log}.
mh_sshd() {  # DIR HOST ADDRESS
  ssh-keygen -q -t ed25519 -N '' -f "$1/hostkey-$2"
  cat > "$1/sshd-$2.conf" <<CONF
ListenAddress $3
Port 22
HostKey $1/hostkey-$2
PidFile $1/sshd-$2.pid
AuthorizedKeysFile $1/authorized_keys
StrictModes no
PermitRootLogin prohibit-password
PasswordAuthentication no
KbdInteractiveAuthentication no
UsePAM no
PrintMotd no
CONF
  ip netns exec "$2" /usr/sbin/sshd -f "$1/sshd-$2.conf" -E "$1/sshd-$2.log"
}
