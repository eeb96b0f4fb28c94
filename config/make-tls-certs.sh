#!/bin/sh
# Test certificates for the TLS deployment (router-tls-acl.json5, planner-tls.json5, user-tls.json5):
# a throw-away CA and a router certificate for localhost / 127.0.0.1 (ECDSA P-256, valid 30 days).
#   sh config/make-tls-certs.sh [DIR]        (default DIR: config/tls; never commit the keys)
# For a real deployment use your own CA and put the router's host names in subjectAltName.
set -eu
dir="${1:-config/tls}"
mkdir -p "$dir"
cd "$dir"
ec="-newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes"
# shellcheck disable=SC2086
openssl req -x509 $ec -keyout ca.key -out ca.pem -days 30 -subj "/CN=eos test CA" 2>/dev/null
# shellcheck disable=SC2086
openssl req $ec -keyout router.key -out router.csr -subj "/CN=localhost" 2>/dev/null
printf "subjectAltName=DNS:localhost,IP:127.0.0.1\nbasicConstraints=CA:FALSE\nkeyUsage=digitalSignature\nextendedKeyUsage=serverAuth\n" > router.ext
openssl x509 -req -in router.csr -CA ca.pem -CAkey ca.key -CAcreateserial -out router.pem -days 30 \
    -extfile router.ext 2>/dev/null
rm -f router.csr router.ext ca.srl
chmod 600 ca.key router.key
echo "wrote $dir/ca.pem, $dir/router.pem, $dir/router.key (and the CA key $dir/ca.key)"
