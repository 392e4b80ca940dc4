#!/bin/sh
# Test DDS Security material for PLR (Cyclone DDS built-in plug-ins):
# a CA (identity CA and permissions CA at once), one identity per name, a
# governance document (authentication, access control and encryption on every
# topic of every domain) and one permissions document per identity, all signed
# by the CA with S/MIME as DDS Security wants.
#
#   scripts/make-dds-certs.sh OUT_DIR [KERNEL_NAME...]
#
# OUT_DIR/<name>/ then holds identity_ca.pem identity.pem identity_key.pem
# permissions_ca.pem governance.p7s permissions.p7s; point a kernel's
# `remote.dds.security_dir` (or `plr monitor|swap --security`) at it.
# Identities made:
#   each KERNEL_NAME (default: kernel)  may publish every PLR topic but commands
#                                       (plr/control) and read every topic
#   operator                            may send commands (plr/control) and read everything
#   monitor                             may only read
# A test CA: keep the real one's key off the robots.
set -eu
set -f  # topic expressions are patterns, not file names

out=${1:?usage: make-dds-certs.sh OUT_DIR [KERNEL_NAME...]}
shift
kernels=${*:-kernel}
mkdir -p "$out"
umask 077
cd "$out"

openssl req -x509 -newkey rsa:2048 -nodes -days 3650 -sha256 \
  -subj "/C=NL/O=PLR/CN=PLR test CA" -keyout ca_key.pem -out ca.pem 2>/dev/null

cat > governance.xml <<'EOF'
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170801/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>0</min><max>230</max></id_range></domains>
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
openssl smime -sign -in governance.xml -text -out governance.p7s \
  -signer ca.pem -inkey ca_key.pem 2>/dev/null

# permissions NAME PUBLISH_EXPRESSIONS
permissions() {
  name=$1
  publish=$2
  {
    cat <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170801/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="${name}">
      <subject_name>CN=${name},O=PLR,C=NL</subject_name>
      <validity><not_before>2020-01-01T00:00:00</not_before><not_after>2040-01-01T00:00:00</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>230</max></id_range></domains>
EOF
    if [ -n "$publish" ]; then
      echo "        <publish><topics>"
      for t in $publish; do echo "          <topic>$t</topic>"; done
      echo "        </topics></publish>"
    fi
    cat <<EOF
        <subscribe><topics><topic>*</topic><topic>*/*</topic><topic>*/*/*</topic><topic>*/*/*/*</topic><topic>*/*/*/*/*</topic></topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
EOF
  } > "$name/permissions.xml"
  openssl smime -sign -in "$name/permissions.xml" -text -out "$name/permissions.p7s" \
    -signer ca.pem -inkey ca_key.pem 2>/dev/null
}

identity() {
  name=$1
  publish=$2
  mkdir -p "$name"
  openssl req -newkey rsa:2048 -nodes -sha256 -subj "/C=NL/O=PLR/CN=${name}" \
    -keyout "$name/identity_key.pem" -out "$name/identity.csr" 2>/dev/null
  openssl x509 -req -in "$name/identity.csr" -CA ca.pem -CAkey ca_key.pem -CAcreateserial \
    -days 3650 -sha256 -out "$name/identity.pem" 2>/dev/null
  rm -f "$name/identity.csr"
  cp ca.pem "$name/identity_ca.pem"
  cp ca.pem "$name/permissions_ca.pem"
  cp governance.p7s "$name/governance.p7s"
  permissions "$name" "$publish"
  echo "$out/$name"
}

# Kernels publish their data, announces, telemetry, calls and command
# results, never commands: a stolen kernel key cannot control the others.
# Listed one by one: Cyclone refuses even to create a topic a deny_rule names.
kernel_topics="plr/announce plr/telemetry plr/result plr/request plr/reply"
kernel_topics="$kernel_topics plr/topic/* plr/topic/*/* plr/topic/*/*/* plr/topic/*/*/*/*"
for k in $kernels; do identity "$k" "$kernel_topics"; done
identity operator "plr/control plr/announce"
identity monitor ""
