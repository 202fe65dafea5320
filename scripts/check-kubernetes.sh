#!/usr/bin/env bash
# Checks docs/kubernetes-shards.yaml and docs/kubernetes-collect.yaml against the
# Kubernetes API schemas, strictly (an unknown or misspelt key fails), with
# kubernetes-validate from PyPI, which carries the schemas of each Kubernetes release;
# installed into a throwaway virtual environment. No cluster is involved: this checks
# the manifests' shape, not that a cluster runs them.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
venv=$(mktemp -d)
trap 'rm -rf "$venv"' EXIT
python3 -m venv "$venv"
"$venv/bin/pip" install --quiet kubernetes-validate==1.37.0
"$venv/bin/kubernetes-validate" --strict --kubernetes-version 1.37.0 \
    "$repo/docs/kubernetes-shards.yaml" "$repo/docs/kubernetes-collect.yaml"
