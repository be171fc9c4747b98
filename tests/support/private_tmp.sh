# Sourced by the scripts that give a test private mount namespaces:
#   mount_private_tmp PATH...
# mounts an empty tmpfs on /tmp in the current (private) mount namespace, keeping each
# PATH that lives under /tmp (a clone there, its build, ../shared beside it, a test's
# work folder): its top folder is bind-mounted aside first and moved onto the new /tmp.
mount_private_tmp() {
  local kept=() path top aside=""
  for path in "$@"; do
    [[ $path == /tmp/* && -e $path ]] || continue
    top=${path#/tmp/}
    top=${top%%/*}
    [[ " ${kept[*]-} " == *" $top "* ]] || kept+=("$top")
  done
  if ((${#kept[@]})); then
    aside=$(mktemp -d /run/afhub-test-keep.XXXXXX)
    for top in "${kept[@]}"; do
      mkdir "$aside/$top"
      mount --bind "/tmp/$top" "$aside/$top"
    done
  fi
  mount -t tmpfs -o mode=1777 tmpfs /tmp
  for top in "${kept[@]}"; do
    mkdir "/tmp/$top"
    mount --move "$aside/$top" "/tmp/$top"
    rmdir "$aside/$top"
  done
  if [[ -n $aside ]]; then rmdir "$aside"; fi
}
