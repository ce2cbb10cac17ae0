#!/bin/sh
# A stand-in for Visual Studio's cl, lib, rc and mc (scripts/check-msvc-build-script.sh): records its
# name and arguments in $OPCCOMN_TOOL_LOG and writes the file each would write, so the build script's
# calls can be checked on a machine without Visual Studio.
tool=$(basename "$0")
echo "$tool $*" >>"$OPCCOMN_TOOL_LOG"
case "$tool" in
    mc)  # -r DIR -h DIR FILE.mc: writes FILE.rc (and FILE.h) in the directories named
        printf 'LANGUAGE 0x9,0x1\n1 11 "MSG00409.bin"\n' >opccomn_messages.rc
        : >opccomn_messages.h ;;
    rc)  # /fo OUT IN
        shift 2; : >"$1" ;;
    cl)  # /Fo<object> among the arguments
        for a in "$@"; do case "$a" in /Fo*) : >"${a#/Fo}" ;; esac; done ;;
    lib) # /OUT:<library> among the arguments
        for a in "$@"; do case "$a" in /OUT:*) : >"${a#/OUT:}" ;; esac; done ;;
    *) echo "tool-stand-in.sh: unknown tool $tool" >&2; exit 2 ;;
esac
