#!/usr/bin/env bash
# An SROS2 keystore as `ros2 security create_keystore` / `create_enclave` write it, made
# with the OpenSSL command line (PyPI has no sros2): one CA (prime256v1) serving as
# identity and permissions CA, a governance signed for domain $ROS_DOMAIN_ID (default 0)
# that authenticates, encrypts and access-controls everything, and per enclave an identity
# (CN=<enclave>) with a signed permissions document.
#
#   sros2-keystore.sh create_keystore KEYSTORE
#   sros2-keystore.sh create_enclave KEYSTORE ENCLAVE [DENIED_TOPIC...]
#
# An enclave's permissions are sros2's default policy (every topic, service and action)
# unless topics are named: publishing and subscribing those (`/chatter` is DDS topic
# `rt/chatter`) is then denied, everything else allowed. KEYSTORE/private holds the CA key.
set -euo pipefail

domain=${ROS_DOMAIN_ID:-0}

# openssl's configuration for our certificates only (not the system's, whose defaults vary).
conf() {
    cat <<EOF
[req]
distinguished_name = dn
[dn]
[ca]
basicConstraints = critical,CA:TRUE,pathlen:1
[leaf]
basicConstraints = CA:FALSE
EOF
}

sign() { # sign IN OUT: S/MIME, clear-signed text, by the permissions CA (as sros2)
    openssl smime -sign -text -in "$2/$1" -out "$2/$3" \
        -signer "$ks/public/permissions_ca.cert.pem" -inkey "$ks/private/permissions_ca.key.pem"
}

create_keystore() {
    mkdir -p "$ks/public" "$ks/private" "$ks/enclaves"
    local c
    c=$(mktemp)
    conf >"$c"
    openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:prime256v1 -out "$ks/private/ca.key.pem" 2>/dev/null
    openssl req -new -x509 -config "$c" -extensions ca -key "$ks/private/ca.key.pem" \
        -subj "/CN=sros2CA" -days 3650 -sha256 -out "$ks/public/ca.cert.pem"
    rm -f "$c"
    for f in identity_ca permissions_ca; do
        ln -sf ca.cert.pem "$ks/public/$f.cert.pem"
        ln -sf ca.key.pem "$ks/private/$f.key.pem"
    done
    cat >"$ks/enclaves/governance.xml" <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
    xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id>$domain</id></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
EOF
    sign governance.xml "$ks/enclaves" governance.p7s
}

# sros2's default policy, as its permissions template expands it.
topics() {
    local t
    for t in 'rt/*' 'rq/*Request' 'rr/*Reply' 'rq/*/_action/send_goalRequest' \
        'rq/*/_action/cancel_goalRequest' 'rq/*/_action/get_resultRequest' \
        'rr/*/_action/send_goalReply' 'rr/*/_action/cancel_goalReply' \
        'rr/*/_action/get_resultReply' 'rt/*/_action/feedback' 'rt/*/_action/status'; do
        echo "<topic>$t</topic>"
    done
}

create_enclave() {
    local enclave=$1
    shift
    [[ $enclave == /* ]] || { echo "enclave $enclave: must start with /" >&2; exit 2; }
    [[ -f $ks/enclaves/governance.p7s ]] || { echo "$ks: not a keystore" >&2; exit 2; }
    local rel=${enclave#/} d up c
    d=$ks/enclaves/$rel
    mkdir -p "$d"
    up=$(realpath --relative-to="$d" "$ks")
    ln -sf "$up/public/identity_ca.cert.pem" "$d/identity_ca.cert.pem"
    ln -sf "$up/public/permissions_ca.cert.pem" "$d/permissions_ca.cert.pem"
    ln -sf "$(realpath --relative-to="$d" "$ks/enclaves")/governance.p7s" "$d/governance.p7s"
    c=$(mktemp)
    conf >"$c"
    openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:prime256v1 -out "$d/key.pem" 2>/dev/null
    openssl req -new -config "$c" -key "$d/key.pem" -subj "/CN=${enclave//\//\\/}" |
        openssl x509 -req -CA "$ks/public/identity_ca.cert.pem" -CAkey "$ks/private/identity_ca.key.pem" \
            -CAcreateserial -CAserial "$ks/private/serial" -extfile "$c" -extensions leaf \
            -days 3650 -sha256 -out "$d/cert.pem" 2>/dev/null
    rm -f "$c"
    local deny="" t now until
    if (($# > 0)); then
        deny="<deny_rule><domains><id>$domain</id></domains>"
        for side in publish subscribe; do
            deny+="<$side><topics>"
            for t in "$@"; do deny+="<topic>rt$t</topic>"; done
            deny+="</topics></$side>"
        done
        deny+="</deny_rule>"
    fi
    now=$(date -u +%Y-%m-%dT%H:%M:%S)
    until=$(date -u -d '+10 years' +%Y-%m-%dT%H:%M:%S)
    cat >"$d/permissions.xml" <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
    xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$enclave">
      <subject_name>CN=$enclave</subject_name>
      <validity><not_before>$now</not_before><not_after>$until</not_after></validity>
      $deny
      <allow_rule>
        <domains><id>$domain</id></domains>
        <publish><topics>$(topics)</topics></publish>
        <subscribe><topics>$(topics)</topics></subscribe>
      </allow_rule>
      <allow_rule>
        <domains><id>$domain</id></domains>
        <publish><topics><topic>ros_discovery_info</topic></topics></publish>
        <subscribe><topics><topic>ros_discovery_info</topic></topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
EOF
    sign permissions.xml "$d" permissions.p7s
}

case ${1:-} in
create_keystore)
    ks=$2
    create_keystore
    ;;
create_enclave)
    ks=$2
    shift 2
    create_enclave "$@"
    ;;
*)
    sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
    ;;
esac
