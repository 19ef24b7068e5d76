# Sourced by quickstart.sh, ci-extra.sh, fuzz.sh and package.sh: installs the
# Debian packages given that the machine lacks, in one apt-get call, and
# nothing when it has them all (so a second run does not touch apt at all).
#
#   source scripts/packages.sh; install_missing g++ cmake ...
install_missing() {
  local sudo="" p missing=()
  [[ $(id -u) -ne 0 ]] && sudo="sudo"
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  ((${#missing[@]})) || return 0
  echo "installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}
