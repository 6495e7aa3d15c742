//! The bridge's refusals are typed (`drivemap_bridge::Error`) and still say where: the option
//! and the URL, the CA file by path, the listener's address.

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use drivemap_bridge::{Error, mqtt};

#[test]
fn mqtt_urls_are_refused_naming_the_url() {
    let e = mqtt::parse_url("http://broker").unwrap_err();
    assert!(matches!(&e, Error::MqttScheme { url } if url == "http://broker"));
    assert_eq!(
        e.to_string(),
        "--mqtt http://broker: give mqtt://HOST[:PORT] or mqtts://HOST[:PORT] (TLS)"
    );
    let e = mqtt::parse_url("mqtt://broker:99999").unwrap_err();
    assert!(
        matches!(&e, Error::MqttPort { port, .. } if port == "99999"),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        "--mqtt mqtt://broker:99999: `99999` is not a port"
    );
    let e = mqtt::parse_url("mqtts://:8883").unwrap_err();
    assert_eq!(e.to_string(), "--mqtt mqtts://:8883: no host");
    assert_eq!(
        mqtt::parse_url("mqtts://[::1]:8884/").unwrap(),
        (true, "::1".to_owned(), 8884)
    );
}

#[test]
fn a_ca_file_is_refused_by_its_path() {
    let dir = std::env::temp_dir().join(format!("drivemap-bridge-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("missing.pem");
    let e = mqtt::tls_config(&missing).unwrap_err();
    assert!(
        matches!(&e, Error::Ca { path, .. } if *path == missing),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .starts_with(&format!("--mqtt-ca {}: ", missing.display())),
        "{e}"
    );
    let empty = dir.join("empty.pem");
    std::fs::write(&empty, "no certificate here\n").unwrap();
    let e = mqtt::tls_config(&empty).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("--mqtt-ca {}: no certificate in it", empty.display())
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_bridge_without_drives_or_with_a_taken_port_says_so() {
    let options = drivemap_bridge::Options {
        period: Duration::from_millis(100),
        metrics: None,
        mqtt: None,
        deadline: drivemap_bridge::command::DEFAULT_DEADLINE,
    };
    let e = drivemap_bridge::run(Vec::new(), options, Arc::new(AtomicBool::new(true)));
    assert!(matches!(e, Err(Error::NoDrives)), "{e:?}");
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr: SocketAddr = taken.local_addr().unwrap();
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let e = runtime
        .block_on(drivemap_bridge::metrics::bind(addr))
        .unwrap_err();
    assert!(
        matches!(&e, Error::Metrics { addr: a, .. } if *a == addr),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .starts_with(&format!("cannot listen for /metrics on {addr}: ")),
        "{e}"
    );
}

/// Credentials in the broker URL are refused without being repeated; topic roots that cannot
/// be published under are refused with why.
#[test]
fn credentials_in_the_url_and_wildcard_roots_are_refused() {
    let e = mqtt::parse_url("mqtt://bridge:s3cret@broker.local:1883").unwrap_err();
    assert!(matches!(e, Error::MqttUserinfo { .. }), "{e:?}");
    let text = e.to_string();
    assert!(
        !text.contains("s3cret") && !text.contains("bridge:"),
        "{text}"
    );
    assert!(text.contains("broker.local:1883"), "{text}");
    for (root, why) in [
        ("plant/+", "wildcards"),
        ("ha/#", "wildcards"),
        ("", "empty"),
        ("a//b", "empty level"),
        ("/a", "empty level"),
        ("$SYS", "broker's"),
    ] {
        let e = mqtt::check_topic_root("--mqtt-topic", root).unwrap_err();
        assert!(e.to_string().contains(why), "{root}: {e}");
    }
    for root in ["drivemap", "plant/hall-2/drives", "homeassistant"] {
        mqtt::check_topic_root("--mqtt-topic", root).unwrap();
    }
}
