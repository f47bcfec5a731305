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

# Makes sure QEMU's BINARY (qemu-system-arm, qemu-system-x86_64) is version 10 or newer, installing PACKAGE from
# bookworm-backports otherwise (bookworm's 7.2 cannot be installed beside the machine's qemu-utils 10). LABEL
# prefixes the messages.
ensure_qemu10() {
    local binary="$1" package="$2" label="$3" major
    major() {
        command -v "${binary}" >/dev/null 2>&1 || return 0
        "${binary}" --version | sed -n 's/^QEMU emulator version \([0-9]*\)\..*/\1/p' | head -n 1
    }
    major="$(major)"
    if [ -z "${major}" ] || [ "${major}" -lt 10 ]; then
        echo "${label}: installing ${package} from bookworm-backports (found: ${major:-none})"
        install_from_backports "${package}"
        major="$(major)"
        if [ -z "${major}" ] || [ "${major}" -lt 10 ]; then
            echo "${label}: ${package} 10 or newer is required, got '${major:-none}'" >&2
            return 1
        fi
    fi
    echo "${label}: $("${binary}" --version | head -n 1)"
}
