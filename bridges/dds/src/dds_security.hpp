// `afhub bridge dds --security DIR`: DDS Security (authentication, access control,
// encryption; the plugins ship in Debian's libddsc0debian) for the bridge's
// participant. DIR holds, by these names (bridges/dds/security/make_credentials.sh
// makes them; the README shows the openssl steps):
//   identity_ca.pem            the CA that signs every participant's certificate
//   identity_certificate.pem   this participant's certificate (signed by that CA)
//   identity_private_key.pem   its private key
//   permissions_ca.pem         the CA that signs governance and permissions
//   governance.p7s             the domain's rules (signed by the permissions CA)
//   permissions.p7s            what this participant's subject may publish and
//                              subscribe (signed by the permissions CA)
#pragma once

#include <dds/dds.h>

#include <string>

namespace afhub::bridges {

// Adds the security properties for DIR to `qos`. Throws afhub::Error naming the
// first missing or unreadable file.
void add_security_properties(dds_qos_t* qos, const std::string& dir);

}  // namespace afhub::bridges
