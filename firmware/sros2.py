"""SROS2 keystore for the rig's enclaves (`rig-device sros2-keys`): the keystore and one enclave per
compose service that runs ROS 2 nodes (`context.enclaves`), so that with `on_device.sros2_enclaves` every
node authenticates and only the rig's participants join its DDS domain.

Two ways to the same layout, the first one available:

- `ros2 security create_keystore DIR` then `ros2 security create_enclave DIR NAME` (the sros2 package:
  what the ROS images ship) when `ros2` is on PATH;
- otherwise this module writes the keystore layout sros2 writes, with the `cryptography` library:

      public/ca.cert.pem               the self-signed CA (EC P-256, CN sros2CA), also identity_ca.cert.pem
                                       and permissions_ca.cert.pem (one CA for both, as sros2 does)
      private/ca.key.pem               its key (mode 0600, folder 0700), also identity_ca / permissions_ca
      enclaves/governance.xml, .p7s    the DDS-Security governance of the rig's domain, S/MIME signed
      enclaves/<name>/cert.pem, key.pem   the enclave's identity (CN = the enclave name), signed by the CA
      enclaves/<name>/permissions.xml, .p7s   its grant (publish and subscribe in the rig's domain)
      enclaves/<name>/governance.p7s, identity_ca.cert.pem, permissions_ca.cert.pem   what the DDS
                                       security plugins load from the enclave folder

The S/MIME files are signed as sros2 signs them (detached, text, SHA-256), so `openssl smime -verify`
reads them; tests verify the chain with `openssl verify`, independently of this module.
"""
from __future__ import annotations

import datetime as dt
import os
import shutil
import subprocess
from pathlib import Path, PurePosixPath
from typing import Callable, Iterable

#: the CA's common name, as sros2 names it
CA_NAME = "sros2CA"
#: how long the CA and the enclave certificates and grants are valid (sros2: 10 years)
VALIDITY_DAYS = 3650
#: the file names every enclave folder holds (what the DDS security plugins load)
ENCLAVE_FILES = ("cert.pem", "key.pem", "permissions.xml", "permissions.p7s", "governance.p7s",
                 "identity_ca.cert.pem", "permissions_ca.cert.pem")
_XSD = "http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_{}.xsd"


class KeystoreError(Exception):
    """The keystore cannot be made: the message names the folder, the enclave or the tool."""


def enclave_dir(keystore: Path, name: str) -> Path:
    """/rgbt/zed -> <keystore>/enclaves/rgbt/zed. A name must be absolute, without '..'."""
    p = PurePosixPath(name)
    if not p.is_absolute() or ".." in p.parts or len(p.parts) < 2:
        raise KeystoreError(f"enclave {name!r}: expected an absolute name like /rgbt/zed")
    return keystore.joinpath("enclaves", *p.parts[1:])


# ----------------------------------------------------------------------------- the XML documents (pure)
def governance_xml(domain_id: int) -> str:
    """Governance of the rig's one domain: no unauthenticated participant, join access control, every
    topic's discovery, liveliness, data and metadata encrypted, read and write access controlled."""
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="{_XSD.format('governance')}">
  <domain_access_rules>
    <domain_rule>
      <domains>
        <id>{domain_id}</id>
      </domains>
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
"""


def _stamp(t: dt.datetime) -> str:
    return t.astimezone(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%S")


def permissions_xml(name: str, domain_id: int, not_before: dt.datetime, not_after: dt.datetime) -> str:
    """The grant of one enclave: its subject (CN = the enclave name), its validity, publish and subscribe
    in the rig's domain, everything else denied."""
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="{_XSD.format('permissions')}">
  <permissions>
    <grant name="{name}">
      <subject_name>CN={name}</subject_name>
      <validity>
        <not_before>{_stamp(not_before)}</not_before>
        <not_after>{_stamp(not_after)}</not_after>
      </validity>
      <allow_rule>
        <domains>
          <id>{domain_id}</id>
        </domains>
        <publish>
          <topics>
            <topic>*</topic>
          </topics>
        </publish>
        <subscribe>
          <topics>
            <topic>*</topic>
          </topics>
        </subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
"""


# ----------------------------------------------------------------------------- keys with `cryptography`
def _crypto():
    try:
        from cryptography import x509
        from cryptography.hazmat.primitives import hashes, serialization
        from cryptography.hazmat.primitives.asymmetric import ec
        from cryptography.hazmat.primitives.serialization import pkcs7
        from cryptography.x509.oid import NameOID
    except ImportError:
        raise KeystoreError("neither `ros2` (ros2 security) nor the Python `cryptography` library is available: "
                            "run this in a ROS image, or pip install cryptography") from None
    return x509, hashes, serialization, ec, pkcs7, NameOID


def _cert(subject: str, key, issuer_name, issuer_key, now: dt.datetime, *, ca: bool):
    x509, hashes, _, _, _, NameOID = _crypto()
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, subject)])
    builder = (x509.CertificateBuilder().subject_name(name).issuer_name(issuer_name or name)
               .public_key(key.public_key()).serial_number(x509.random_serial_number())
               .not_valid_before(now).not_valid_after(now + dt.timedelta(days=VALIDITY_DAYS))
               .add_extension(x509.BasicConstraints(ca=ca, path_length=1 if ca else None), critical=True))
    return builder.sign(issuer_key or key, hashes.SHA256())


def _pem_key(key) -> bytes:
    _, _, serialization, _, _, _ = _crypto()
    return key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                             serialization.NoEncryption())


def _pem_cert(cert) -> bytes:
    _, _, serialization, _, _, _ = _crypto()
    return cert.public_bytes(serialization.Encoding.PEM)


def sign_smime(data: bytes, cert, key) -> bytes:
    """S/MIME clear-signed (detached, text), SHA-256: what `openssl smime -verify` and the DDS security
    plugins read."""
    _, hashes, serialization, _, pkcs7, _ = _crypto()
    return (pkcs7.PKCS7SignatureBuilder().set_data(data).add_signer(cert, key, hashes.SHA256())
            .sign(serialization.Encoding.SMIME, [pkcs7.PKCS7Options.Text, pkcs7.PKCS7Options.DetachedSignature]))


def _write(path: Path, data: bytes, mode: int = 0o644) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)
    path.chmod(mode)


def _link(path: Path, target: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.symlink_to(target)


def create_keystore(keystore: Path, domain_id: int, now: dt.datetime) -> tuple:
    """The CA and the signed governance, in an empty folder. Returns (ca_cert, ca_key)."""
    _, _, _, ec, _, _ = _crypto()
    key = ec.generate_private_key(ec.SECP256R1())
    cert = _cert(CA_NAME, key, None, None, now, ca=True)
    _write(keystore / "public" / "ca.cert.pem", _pem_cert(cert))
    (keystore / "private").mkdir(parents=True, exist_ok=True)
    (keystore / "private").chmod(0o700)
    _write(keystore / "private" / "ca.key.pem", _pem_key(key), 0o600)
    for role in ("identity_ca", "permissions_ca"):
        _link(keystore / "public" / f"{role}.cert.pem", "ca.cert.pem")
        _link(keystore / "private" / f"{role}.key.pem", "ca.key.pem")
    gov = governance_xml(domain_id).encode()
    _write(keystore / "enclaves" / "governance.xml", gov)
    _write(keystore / "enclaves" / "governance.p7s", sign_smime(gov, cert, key))
    return cert, key


def create_enclave(keystore: Path, name: str, domain_id: int, ca: tuple, now: dt.datetime) -> Path:
    """One enclave's identity and grant, signed by the keystore's CA."""
    _, _, _, ec, _, _ = _crypto()
    ca_cert, ca_key = ca
    folder = enclave_dir(keystore, name)
    key = ec.generate_private_key(ec.SECP256R1())
    cert = _cert(name, key, ca_cert.subject, ca_key, now, ca=False)
    _write(folder / "cert.pem", _pem_cert(cert))
    _write(folder / "key.pem", _pem_key(key), 0o600)
    perms = permissions_xml(name, domain_id, now, now + dt.timedelta(days=VALIDITY_DAYS)).encode()
    _write(folder / "permissions.xml", perms)
    _write(folder / "permissions.p7s", sign_smime(perms, ca_cert, ca_key))
    up = os.path.relpath(keystore, folder)
    _link(folder / "governance.p7s", f"{up}/enclaves/governance.p7s")
    _link(folder / "identity_ca.cert.pem", f"{up}/public/identity_ca.cert.pem")
    _link(folder / "permissions_ca.cert.pem", f"{up}/public/permissions_ca.cert.pem")
    return folder


# ----------------------------------------------------------------------------- either way
Runner = Callable[[list], "subprocess.CompletedProcess"]


def _run_ros2(argv: list) -> subprocess.CompletedProcess:
    return subprocess.run(argv, capture_output=True, text=True, timeout=120)


def generate(stage: Path, enclave_names: Iterable[str], domain_id: int, *, ros2: str | None = None,
             runner: Runner = _run_ros2, now: dt.datetime | None = None) -> str:
    """Fill the empty folder `stage` with the keystore and the enclaves; returns the tool used ("ros2
    security" or "cryptography"). `ros2`: the ros2 executable (default: the one on PATH, if any)."""
    names = list(enclave_names)
    for n in names:
        enclave_dir(stage, n)       # every name valid before anything is made
    ros2 = ros2 if ros2 is not None else shutil.which("ros2")
    if ros2:
        for argv in ([ros2, "security", "create_keystore", str(stage)],
                     *([ros2, "security", "create_enclave", str(stage), n] for n in names)):
            r = runner(argv)
            if r.returncode != 0:
                why = (r.stderr or r.stdout or "").strip().splitlines()
                raise KeystoreError(f"`{' '.join(argv[1:4])} ...` exited {r.returncode}"
                                    + (f": {why[-1]}" if why else ""))
        return "ros2 security"
    now = now or dt.datetime.now(dt.timezone.utc).replace(microsecond=0)
    ca = create_keystore(stage, domain_id, now)
    for n in names:
        create_enclave(stage, n, domain_id, ca, now)
    return "cryptography"
