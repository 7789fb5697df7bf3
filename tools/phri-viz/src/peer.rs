//! Who is at the other end of a local TCP connection.
//!
//! TCP has no `SO_PEERCRED`, but both ends of a loopback connection are
//! sockets of this machine, and the kernel lists every socket of this
//! network namespace with its owner in `/proc/net/tcp` (IPv4) and
//! `/proc/net/tcp6` (IPv6, IPv4 as `::ffff:a.b.c.d` when the peer used an
//! IPv6 socket). The peer's socket is the entry whose local address is the
//! connection's remote address and whose remote address is the connection's
//! local address; its `uid` column is the user that created it.
//!
//! Read while the accepted socket is held open, the four addresses cannot
//! belong to another connection (the kernel refuses to reuse a 4-tuple in
//! use). Only an established entry counts: a socket in `TIME_WAIT` (or a
//! half-open `SYN_RECV` request) is listed with uid 0, which must not pass
//! for root. A peer not found (another host, or gone already) is refused.

use std::io;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr};

/// The kernel's socket tables, IPv4 then IPv6.
pub const TABLES: [&str; 2] = ["/proc/net/tcp", "/proc/net/tcp6"];

/// `st` of an established connection in the tables.
const ESTABLISHED: u8 = 0x01;

/// One line of a socket table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Entry {
    pub local: SocketAddr,
    pub remote: SocketAddr,
    /// TCP state (`st`; 0x01 established)
    pub state: u8,
    /// the user that created the socket
    pub uid: u32,
}

/// `0100007F:1F90` (IPv4) or 32 hex digits `:port` (IPv6): each 32-bit word
/// is printed as the host reads the address's bytes in memory.
fn parse_addr(s: &str) -> Option<SocketAddr> {
    let (ip, port) = s.split_once(':')?;
    let port = u16::from_str_radix(port, 16).ok()?;
    let word = |i: usize| -> Option<[u8; 4]> {
        let w = ip.get(i * 8..i * 8 + 8)?;
        Some(u32::from_str_radix(w, 16).ok()?.to_ne_bytes())
    };
    let ip = match ip.len() {
        8 => IpAddr::V4(Ipv4Addr::from(word(0)?)),
        32 => {
            let mut b = [0u8; 16];
            for i in 0..4 {
                b[i * 4..i * 4 + 4].copy_from_slice(&word(i)?);
            }
            IpAddr::V6(Ipv6Addr::from(b))
        }
        _ => return None,
    };
    Some(SocketAddr::new(ip, port))
}

/// One data line: `sl local rem st tx:rx tr:when retrnsmt uid timeout inode …`.
fn parse_line(line: &str) -> Option<Entry> {
    let f: Vec<&str> = line.split_whitespace().collect();
    if f.len() < 8 || !f[0].ends_with(':') {
        return None;
    }
    Some(Entry {
        local: parse_addr(f[1])?,
        remote: parse_addr(f[2])?,
        state: u8::from_str_radix(f[3], 16).ok()?,
        uid: f[7].parse().ok()?,
    })
}

/// The entries of a table's text (the header and malformed lines skipped).
pub fn entries(table: &str) -> impl Iterator<Item = Entry> + '_ {
    table.lines().filter_map(parse_line)
}

/// An IPv4 address written as IPv6 (`::ffff:a.b.c.d`) as the IPv4 address it is.
fn canonical(a: SocketAddr) -> SocketAddr {
    match a.ip() {
        IpAddr::V6(v6) => match v6.to_ipv4_mapped() {
            Some(v4) => SocketAddr::new(IpAddr::V4(v4), a.port()),
            None => a,
        },
        IpAddr::V4(_) => a,
    }
}

/// The owner of the socket at `peer` connected to `ours` in `tables`' text;
/// `None` when no established entry matches, or when matches disagree.
pub fn owner_in(tables: &[&str], peer: SocketAddr, ours: SocketAddr) -> Option<u32> {
    let (peer, ours) = (canonical(peer), canonical(ours));
    let mut owner = None;
    for e in tables.iter().flat_map(|t| entries(t)) {
        if e.state != ESTABLISHED || canonical(e.local) != peer || canonical(e.remote) != ours {
            continue;
        }
        match owner {
            None => owner = Some(e.uid),
            Some(u) if u == e.uid => {}
            Some(_) => return None,
        }
    }
    owner
}

/// The owner of the socket at `peer` connected to `ours`, read from the
/// kernel's tables now (a table this kernel lacks, e.g. no IPv6, is empty).
pub fn peer_uid(peer: SocketAddr, ours: SocketAddr) -> io::Result<Option<u32>> {
    let mut texts = Vec::with_capacity(TABLES.len());
    for path in TABLES {
        match std::fs::read_to_string(path) {
            Ok(t) => texts.push(t),
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(io::Error::new(e.kind(), format!("{path}: {e}"))),
        }
    }
    let refs: Vec<&str> = texts.iter().map(String::as_str).collect();
    Ok(owner_in(&refs, peer, ours))
}

/// Whether a socket of `peer_uid` may watch the cell of `own_uid`: the same
/// user, or root (who can read the shared memory anyway).
pub fn admitted(peer_uid: u32, own_uid: u32) -> bool {
    peer_uid == own_uid || peer_uid == 0
}

/// This process's effective uid (the owner of its shared memory).
pub fn own_uid() -> u32 {
    // SAFETY: geteuid(2) cannot fail and touches no memory.
    unsafe { libc::geteuid() }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "  sl  local_address rem_address   st tx_queue rx_queue tr tm->when retrnsmt   uid  timeout inode";

    /// A table line as the kernel prints it.
    fn line(sl: usize, local: SocketAddr, remote: SocketAddr, st: u8, uid: u32) -> String {
        fn addr(a: SocketAddr) -> String {
            let words: Vec<String> = match a.ip() {
                IpAddr::V4(v4) => vec![format!("{:08X}", u32::from_ne_bytes(v4.octets()))],
                IpAddr::V6(v6) => v6
                    .octets()
                    .chunks(4)
                    .map(|c| format!("{:08X}", u32::from_ne_bytes([c[0], c[1], c[2], c[3]])))
                    .collect(),
            };
            format!("{}:{:04X}", words.concat(), a.port())
        }
        format!(
            "{sl:4}: {} {} {st:02X} 00000000:00000000 00:00000000 00000000 {uid:5}        0 {} 1 0000000000000000 20 4 30 10 -1",
            addr(local),
            addr(remote),
            1000 + sl
        )
    }

    fn a(s: &str) -> SocketAddr {
        s.parse().unwrap()
    }

    #[test]
    fn addresses_parse_as_the_kernel_prints_them() {
        // little-endian host: 127.0.0.1:8080 is printed 0100007F:1F90
        if cfg!(target_endian = "little") {
            assert_eq!(parse_addr("0100007F:1F90"), Some(a("127.0.0.1:8080")));
            assert_eq!(
                parse_addr("0000000000000000FFFF00000100007F:2235"),
                Some(a("[::ffff:127.0.0.1]:8757"))
            );
            assert_eq!(
                parse_addr("00000000000000000000000001000000:0016"),
                Some(a("[::1]:22"))
            );
        }
        for s in ["", "0100007F", "0100007F:", "zz00007F:1F90", "0100:1F90"] {
            assert_eq!(parse_addr(s), None, "{s}");
        }
    }

    #[test]
    fn the_peers_owner_is_read_from_its_own_entry() {
        let ours = a("127.0.0.1:8765");
        let peer = a("127.0.0.1:40000");
        let table = [
            HEADER.to_string(),
            // the listener and our accepted end: ours, not the peer's
            line(0, ours, a("0.0.0.0:0"), 0x0A, 0),
            line(1, ours, peer, ESTABLISHED, 0),
            // the peer's socket, created by uid 65534
            line(2, peer, ours, ESTABLISHED, 65534),
            "garbage line".to_string(),
        ]
        .join("\n");
        assert_eq!(owner_in(&[&table], peer, ours), Some(65534));
        assert!(!admitted(65534, 0), "another user");
        assert!(admitted(1000, 1000), "the same user");
        assert!(admitted(0, 1000), "root");
        // another connection's port: not found, refused
        assert_eq!(owner_in(&[&table], a("127.0.0.1:40001"), ours), None);
    }

    #[test]
    fn an_ipv6_socket_connected_to_ipv4_is_found_in_tcp6() {
        let ours = a("127.0.0.1:8765");
        let peer = a("127.0.0.1:40000");
        let tcp = [HEADER.to_string(), line(0, ours, peer, ESTABLISHED, 1000)].join("\n");
        let tcp6 = [
            HEADER.to_string(),
            line(
                0,
                a("[::ffff:127.0.0.1]:40000"),
                a("[::ffff:127.0.0.1]:8765"),
                ESTABLISHED,
                4242,
            ),
        ]
        .join("\n");
        assert_eq!(owner_in(&[&tcp, &tcp6], peer, ours), Some(4242));
        // and a server on ::1
        let ours6 = a("[::1]:8765");
        let peer6 = a("[::1]:40000");
        let t = [HEADER.to_string(), line(0, peer6, ours6, ESTABLISHED, 7)].join("\n");
        assert_eq!(owner_in(&[&t], peer6, ours6), Some(7));
    }

    #[test]
    fn time_wait_and_disagreeing_entries_are_refused() {
        let ours = a("127.0.0.1:8765");
        let peer = a("127.0.0.1:40000");
        // a TIME_WAIT socket is listed with uid 0: not root's
        let t = [HEADER.to_string(), line(0, peer, ours, 0x06, 0)].join("\n");
        assert_eq!(owner_in(&[&t], peer, ours), None);
        let t = [
            HEADER.to_string(),
            line(0, peer, ours, ESTABLISHED, 1000),
            line(1, peer, ours, ESTABLISHED, 0),
        ]
        .join("\n");
        assert_eq!(owner_in(&[&t], peer, ours), None);
    }

    #[test]
    fn a_real_loopback_connection_is_ours() {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let client = std::net::TcpStream::connect(listener.local_addr().unwrap()).unwrap();
        let (server, peer) = listener.accept().unwrap();
        assert_eq!(peer, client.local_addr().unwrap());
        let uid = peer_uid(peer, server.local_addr().unwrap()).unwrap();
        assert_eq!(uid, Some(own_uid()));
    }
}
