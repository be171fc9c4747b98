// DDS Security properties for a participant (see dds_security.hpp).
#include "dds_security.hpp"

#include <limits.h>
#include <stdlib.h>
#include <unistd.h>

#include "afhub/shm_layout/error.hpp"

namespace afhub::bridges {
namespace {

struct CredentialFile {
  const char* property;
  const char* file;
  const char* what;
};

constexpr CredentialFile kFiles[] = {
    {"dds.sec.auth.identity_ca", "identity_ca.pem", "the identity CA's certificate"},
    {"dds.sec.auth.identity_certificate", "identity_certificate.pem",
     "this participant's certificate, signed by the identity CA"},
    {"dds.sec.auth.private_key", "identity_private_key.pem", "this participant's private key"},
    {"dds.sec.access.permissions_ca", "permissions_ca.pem", "the permissions CA's certificate"},
    {"dds.sec.access.governance", "governance.p7s",
     "the domain's governance, signed by the permissions CA"},
    {"dds.sec.access.permissions", "permissions.p7s",
     "this participant's permissions, signed by the permissions CA"},
};

// The builtin plugins by Cyclone's names (Debian's libddsc finds them in its own
// libddsc0debian directory).
constexpr const char* kLibraries[][2] = {
    {"dds.sec.auth.library.path", "dds_security_auth"},
    {"dds.sec.auth.library.init", "init_authentication"},
    {"dds.sec.auth.library.finalize", "finalize_authentication"},
    {"dds.sec.crypto.library.path", "dds_security_crypto"},
    {"dds.sec.crypto.library.init", "init_crypto"},
    {"dds.sec.crypto.library.finalize", "finalize_crypto"},
    {"dds.sec.access.library.path", "dds_security_ac"},
    {"dds.sec.access.library.init", "init_access_control"},
    {"dds.sec.access.library.finalize", "finalize_access_control"},
};

}  // namespace

void add_security_properties(dds_qos_t* qos, const std::string& dir) {
  if (dir.empty()) throw Error("--security needs a directory");
  char absolute[PATH_MAX];
  if (!realpath(dir.c_str(), absolute))
    throw Error("--security " + dir +
                ": no such directory; make one with bridges/dds/security/make_credentials.sh");
  for (const CredentialFile& credential : kFiles) {
    const std::string path = std::string(absolute) + "/" + credential.file;
    if (access(path.c_str(), R_OK) != 0)
      throw Error("--security " + dir + ": " + credential.file + " (" + credential.what +
                  ") is missing or unreadable; make the files with "
                  "bridges/dds/security/make_credentials.sh (see bridges/dds/security/README.md)");
    dds_qset_prop(qos, credential.property, ("file:" + path).c_str());
  }
  for (const auto& [property, value] : kLibraries) dds_qset_prop(qos, property, value);
}

}  // namespace afhub::bridges
