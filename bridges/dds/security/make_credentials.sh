#!/usr/bin/env bash
# Makes DDS Security credentials for `afhub bridge dds --security DIR` with openssl:
# an identity CA and a permissions CA, the domain's governance (signed), and for each
# NAME a directory OUT/NAME holding what a participant needs:
#   identity_ca.pem identity_certificate.pem identity_private_key.pem
#   permissions_ca.pem governance.p7s permissions.p7s
# NAME's certificate has subject CN=NAME,O=afhub and its permissions allow it to
# publish and subscribe every topic in domains 0-230 (the most Cyclone's parser takes). The governance refuses
# unauthenticated participants, checks every reader and writer against the
# permissions, and encrypts discovery, liveliness and data.
# Usage: make_credentials.sh OUT NAME... (e.g. make_credentials.sh creds bridge console)
# The CA keys stay in OUT/ca: keep them off the machines that run participants.
set -euo pipefail
if [[ $# -lt 2 ]]; then
  echo "usage: make_credentials.sh OUT NAME... (one directory of credentials per NAME)" >&2
  exit 1
fi
out=$1
shift
days=3650
mkdir -p "$out/ca"
ca=$out/ca

# The two CAs: EC P-256 keys (Cyclone's auth plugin takes P-256 or RSA-2048), each a
# self-signed certificate. Made once; later calls add participants to the same CAs.
for kind in identity permissions; do
  if [[ ! -f $ca/${kind}_ca.pem ]]; then
    openssl ecparam -name prime256v1 -genkey -noout -out "$ca/${kind}_ca_key.pem"
    openssl req -x509 -new -key "$ca/${kind}_ca_key.pem" -days $days \
      -subj "/O=afhub/CN=afhub $kind CA" -out "$ca/${kind}_ca.pem"
  fi
done

# Governance: what the domain protects, signed by the permissions CA (S/MIME, text).
cat >"$ca/governance.xml" <<'XML'
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>0</min><max>230</max></id_range></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>SIGN</rtps_protection_kind>
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
XML
openssl smime -sign -text -in "$ca/governance.xml" -out "$ca/governance.p7s" \
  -signer "$ca/permissions_ca.pem" -inkey "$ca/permissions_ca_key.pem"

for name in "$@"; do
  dir=$out/$name
  mkdir -p "$dir"
  # The participant's key and certificate, signed by the identity CA.
  openssl ecparam -name prime256v1 -genkey -noout -out "$dir/identity_private_key.pem"
  openssl req -new -key "$dir/identity_private_key.pem" -subj "/O=afhub/CN=$name" \
    -out "$dir/request.csr"
  openssl x509 -req -in "$dir/request.csr" -days $days -CA "$ca/identity_ca.pem" \
    -CAkey "$ca/identity_ca_key.pem" -CAcreateserial -out "$dir/identity_certificate.pem" 2>/dev/null
  rm "$dir/request.csr"
  # Its permissions: this subject may publish and subscribe everything, signed by the
  # permissions CA. Narrow <topic> to restrict (e.g. rt/afhub/arm/* for a viewer).
  cat >"$dir/permissions.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$name">
      <subject_name>CN=$name,O=afhub</subject_name>
      <validity><not_before>2020-01-01T00:00:00</not_before><not_after>2100-01-01T00:00:00</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>230</max></id_range></domains>
        <publish><topics><topic>*</topic></topics></publish>
        <subscribe><topics><topic>*</topic></topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
XML
  openssl smime -sign -text -in "$dir/permissions.xml" -out "$dir/permissions.p7s" \
    -signer "$ca/permissions_ca.pem" -inkey "$ca/permissions_ca_key.pem"
  cp "$ca/identity_ca.pem" "$ca/permissions_ca.pem" "$ca/governance.p7s" "$dir/"
  echo "make_credentials: $dir (subject CN=$name,O=afhub)"
done
