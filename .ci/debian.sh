# Sourced by .ci/firmware.sh and tests/vm/setup.sh: the Debian helpers both installers use.

# Runs a command as root: directly when root (CI is), through sudo otherwise.
as_root() {
    if [ "$(id -u)" -eq 0 ]; then
        "$@"
    elif command -v sudo >/dev/null 2>&1; then
        sudo "$@"
    else
        echo "need root to run: $*" >&2
        return 1
    fi
}

# Installs the given packages from bookworm-backports, adding that source first when no source names it (same
# mirror and keyring as the existing bookworm entry).
install_from_backports() {
    local list=/etc/apt/sources.list.d/bookworm-backports.sources uri key
    if ! grep -rqs 'bookworm-backports' /etc/apt/sources.list.d/ /etc/apt/sources.list 2>/dev/null; then
        uri="$(awk '/^URIs:/ {print $2; exit}' /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)"
        key="$(awk '/^Signed-By:/ {print $2; exit}' /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)"
        uri="${uri:-http://deb.debian.org/debian}"
        key="${key:-/usr/share/keyrings/debian-archive-keyring.gpg}"
        printf 'Types: deb\nURIs: %s\nSuites: bookworm-backports\nComponents: main\nSigned-By: %s\n' \
            "${uri}" "${key}" | as_root tee "${list}" >/dev/null
    fi
    as_root env DEBIAN_FRONTEND=noninteractive apt-get update -q
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
        -t bookworm-backports "$@"
}
