"""scripts/check_glibc.sh refuses shared libraries that glibc 2.31 (Ubuntu 20.04) cannot load and
accepts those it can: tiny libraries are built here with the real compiler and linker, against
this machine's glibc and against a provider library with version nodes of our choosing."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
CHECK = REPO / "scripts" / "check_glibc.sh"

pytestmark = pytest.mark.skipif(
    shutil.which("cc") is None or shutil.which("objdump") is None,
    reason="needs a C compiler and objdump (scripts/setup.sh installs both)")


def _build(tmp_path, name, source, *link_args, compiler="cc", suffix=".c"):
    src = tmp_path / (name + suffix)
    src.write_text(source)
    lib = tmp_path / f"lib{name}.so"
    subprocess.run([compiler, "-shared", "-fPIC", "-O1", "-o", str(lib), str(src), *link_args],
                   check=True, capture_output=True, text=True)
    return lib


def _check(*args):
    result = subprocess.run(["bash", str(CHECK), *map(str, args)], capture_output=True, text=True)
    return result.returncode, result.stdout


def _host_glibc():
    return tuple(int(p) for p in os.confstr("CS_GNU_LIBC_VERSION").split()[1].split("."))


# A library whose version nodes are named like glibc's, so a consumer linked against it asks for
# exactly the versions a test chooses, whatever glibc this machine has.
PROVIDER_MAP = """
GLIBC_2.4 { global: at_2_4; local: *; };
GLIBC_2.31 { global: at_2_31; } GLIBC_2.4;
GLIBC_2.32 { global: at_2_32; } GLIBC_2.31;
GLIBC_2.100 { global: at_2_100; } GLIBC_2.32;
GLIBCXX_3.4.28 { global: at_cxx_3_4_28; } GLIBC_2.100;
GLIBCXX_3.4.30 { global: at_cxx_3_4_30; } GLIBCXX_3.4.28;
"""
PROVIDER_C = "\n".join(f"int {n}(void) {{ return {i}; }}" for i, n in enumerate(
    ["at_2_4", "at_2_31", "at_2_32", "at_2_100", "at_cxx_3_4_28", "at_cxx_3_4_30"]))


@pytest.fixture
def provider(tmp_path):
    version_map = tmp_path / "provider.map"
    version_map.write_text(PROVIDER_MAP)
    lib = _build(tmp_path, "provider", PROVIDER_C, f"-Wl,--version-script={version_map}")
    return tmp_path, ["-L", str(tmp_path), "-lprovider"]


def _consumer(provider, name, *functions):
    tmp_path, link = provider
    decls = "".join(f"int {f}(void);\n" for f in functions)
    body = " + ".join(f"{f}()" for f in functions)
    return _build(tmp_path, name, f"{decls}int consume(void) {{ return {body}; }}\n", *link)


@pytest.mark.skipif(_host_glibc() < (2, 34),
                    reason="this glibc versions pthread_create and stat at 2.31 or older")
def test_rejects_a_library_calling_pthread_create_and_stat_of_this_glibc(tmp_path):
    lib = _build(tmp_path, "newsyms", """
#include <pthread.h>
#include <sys/stat.h>
static void *run(void *arg) { return arg; }
int start(const char *path) {
    struct stat st;
    pthread_t thread;
    if (stat(path, &st) != 0) return -1;
    return pthread_create(&thread, 0, run, 0);
}
""", "-pthread")
    rc, out = _check(lib)
    assert rc == 1, out
    assert f"FAIL {lib}" in out
    assert "pthread_create needs GLIBC_2.34 (newer than GLIBC_2.31)" in out
    assert "stat needs GLIBC_2.33 (newer than GLIBC_2.31)" in out
    assert out.splitlines()[-1] == "0 passed, 1 failed"


def test_accepts_a_library_using_only_old_symbols(tmp_path):
    lib = _build(tmp_path, "oldsyms", """
#include <stdlib.h>
#include <string.h>
char *copy(const char *s) {
    size_t n = strlen(s) + 1;
    char *out = malloc(n);
    if (out) memcpy(out, s, n);
    return out;
}
""")
    rc, out = _check(lib)
    assert rc == 0, out
    assert f"PASS {lib}: newest GLIBC_2.14 " in out  # memcpy's version on x86_64
    assert out.splitlines()[-1] == "1 passed, 0 failed"


def test_versions_are_compared_number_by_number(provider):
    # 2.4 and 2.31 are allowed (text order would call 2.4 newer than 2.31); 2.32 and 2.100 are
    # not (text order would call 2.100 older than 2.31).
    old = _consumer(provider, "old", "at_2_4", "at_2_31")
    rc, out = _check(old)
    assert rc == 0, out
    assert "newest GLIBC_2.31 " in out

    for name, function, version in [("new32", "at_2_32", "GLIBC_2.32"),
                                    ("new100", "at_2_100", "GLIBC_2.100")]:
        lib = _consumer(provider, name, "at_2_4", function)
        rc, out = _check(lib)
        assert rc == 1, out
        assert f"{function} needs {version} (newer than GLIBC_2.31)" in out
        assert "at_2_4" not in out


def test_one_check_per_library_and_every_offender_named(provider):
    good = _consumer(provider, "good", "at_2_31")
    bad = _consumer(provider, "bad", "at_2_32", "at_2_100")
    rc, out = _check(good, bad)
    assert rc == 1
    assert f"PASS {good}" in out and f"FAIL {bad}: 2 requirement(s)" in out
    assert "at_2_32 needs GLIBC_2.32" in out and "at_2_100 needs GLIBC_2.100" in out
    assert out.splitlines()[-1] == "1 passed, 1 failed"


@pytest.mark.skipif(shutil.which("c++") is None, reason="needs a C++ compiler")
def test_libstdcxx_is_refused_unless_allowed(tmp_path):
    lib = _build(tmp_path, "cxx", """
#include <string>
extern "C" unsigned long length_of(const char *s) { return std::string(s).size(); }
""", compiler="c++", suffix=".cpp")
    rc, out = _check(lib)
    assert rc == 1, out
    assert "links libstdc++.so.6: the engine is C" in out
    rc, out = _check("--allow-cxx", lib)
    assert rc == 0, out


def test_allowed_cxx_is_held_to_gcc10s_libstdcxx(provider):
    ok = _consumer(provider, "cxxok", "at_cxx_3_4_28")
    assert _check("--allow-cxx", ok)[0] == 0
    too_new = _consumer(provider, "cxxnew", "at_cxx_3_4_30")
    rc, out = _check("--allow-cxx", too_new)
    assert rc == 1, out
    assert "at_cxx_3_4_30 needs GLIBCXX_3.4.30 (newer than GLIBCXX_3.4.28)" in out


def test_missing_file_and_non_library_fail_clearly(tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("not a library\n")
    rc, out = _check(tmp_path / "absent.so", text)
    assert rc == 1
    assert f"FAIL {tmp_path / 'absent.so'}: no such file" in out
    assert f"FAIL {text}: not a shared library" in out
    assert out.splitlines()[-1] == "0 passed, 2 failed"


def test_unknown_option_is_a_usage_error():
    rc, _ = _check("--max=2.35")
    assert rc == 2


# The route the Linux plugin ships by: what is built in the Debian 11 root loads there (glibc 2.31)
# and here and passes the check; the same source built here is refused by the check and by the
# dynamic loader of glibc 2.31 alike, so the check stands for the real failure.
BULLSEYE = REPO / "scripts" / "bullseye_root.sh"

THREADS_C = """
#include <pthread.h>
#include <sys/stat.h>
static void *run(void *arg) { return arg; }
int start(const char *path) {
    struct stat st;
    pthread_t thread;
    void *result = 0;
    if (stat(path, &st) != 0) return -1;
    if (pthread_create(&thread, 0, run, (void *)path) != 0) return -2;
    pthread_join(thread, &result);
    return result == (void *)path ? 0 : -3;
}
"""

LOADER_C = """
#include <dlfcn.h>
#include <gnu/libc-version.h>
#include <stdio.h>
int main(int argc, char **argv) {
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { printf("refused: %s\\n", dlerror()); return 1; }
    int (*start)(const char *) = (int (*)(const char *))dlsym(lib, "start");
    printf("loaded on glibc %s, start() = %d\\n", gnu_get_libc_version(), start(argv[1]));
    return 0;
}
"""


@pytest.mark.skipif(os.geteuid() != 0, reason="debootstrap and chroot need root (CI runs as root)")
@pytest.mark.skipif(_host_glibc() < (2, 34),
                    reason="this glibc versions pthread_create and stat at 2.31 or older")
def test_built_in_the_bullseye_root_loads_on_glibc_2_31_and_a_host_build_does_not(tmp_path):
    # Makes the root when it is missing (a few minutes, once per machine).
    rootfs = Path(subprocess.run(["bash", str(BULLSEYE), "path"], check=True,
                                 capture_output=True, text=True).stdout.strip())
    inside = f"/work/pytest-glibc.{os.getpid()}"
    work = rootfs / inside.lstrip("/")
    work.mkdir(parents=True)
    try:
        (work / "threads.c").write_text(THREADS_C)
        (work / "loader.c").write_text(LOADER_C)

        def in_root(*cmd):
            return subprocess.run(["bash", str(BULLSEYE), "run", *cmd], capture_output=True,
                                  text=True)

        for cmd in (["gcc", "-shared", "-fPIC", "-pthread", "-o", f"{inside}/old.so",
                     f"{inside}/threads.c"],
                    ["gcc", "-o", f"{inside}/loader", f"{inside}/loader.c", "-ldl"]):
            built = in_root(*cmd)
            assert built.returncode == 0, built.stderr
        subprocess.run(["cc", "-shared", "-fPIC", "-pthread", "-o", str(work / "host.so"),
                        str(work / "threads.c")], check=True)
        subprocess.run(["cc", "-o", str(tmp_path / "loader"), str(work / "loader.c"), "-ldl"],
                       check=True)

        old = in_root(f"{inside}/loader", f"{inside}/old.so")
        assert old.returncode == 0 and "loaded on glibc 2.31, start() = 0" in old.stdout, old
        here = subprocess.run([str(tmp_path / "loader"), str(work / "old.so")],
                              capture_output=True, text=True)
        here_version = ".".join(map(str, _host_glibc()))
        assert f"loaded on glibc {here_version}, start() = 0" in here.stdout, here
        assert _check(work / "old.so")[0] == 0

        new = in_root(f"{inside}/loader", f"{inside}/host.so")
        assert new.returncode == 1, new
        assert "refused:" in new.stdout and "not found" in new.stdout, new.stdout
        rc, out = _check(work / "host.so")
        assert rc == 1 and "pthread_create needs GLIBC_2.34" in out, out
    finally:
        shutil.rmtree(work)
