/* A library that exports every function caustica binds from Open Image Denoise 2 (src/denoise/ffi.rs)
   but reports major version 1: tests/denoise.rs builds it with cc and checks that CAUSTICA_OIDN naming
   it is refused by its version before anything is rendered. No function does any work. */
#include <stdbool.h>
#include <stddef.h>
#include <string.h>

static int device;

int oidnGetNumPhysicalDevices(void) { return 0; }
int oidnGetPhysicalDeviceInt(int id, const char *name) { (void)id; (void)name; return 0; }
bool oidnGetPhysicalDeviceBool(int id, const char *name) { (void)id; (void)name; return false; }
const char *oidnGetPhysicalDeviceString(int id, const char *name) { (void)id; (void)name; return NULL; }
const void *oidnGetPhysicalDeviceData(int id, const char *name, size_t *size) { (void)id; (void)name; *size = 0; return NULL; }
void *oidnNewDevice(int type) { (void)type; return &device; }
void *oidnNewDeviceByID(int id) { (void)id; return &device; }
void oidnCommitDevice(void *d) { (void)d; }
int oidnGetDeviceInt(void *d, const char *name) {
    (void)d;
    if (strcmp(name, "versionMajor") == 0) return 1;
    if (strcmp(name, "version") == 0) return 10403;
    return 0;
}
int oidnGetDeviceError(void *d, const char **message) { (void)d; *message = NULL; return 0; }
void oidnReleaseDevice(void *d) { (void)d; }
void *oidnNewBuffer(void *d, size_t size) { (void)d; (void)size; return NULL; }
void oidnWriteBuffer(void *b, size_t offset, size_t size, const void *src) { (void)b; (void)offset; (void)size; (void)src; }
void oidnReadBuffer(void *b, size_t offset, size_t size, void *dst) { (void)b; (void)offset; (void)size; (void)dst; }
void oidnReleaseBuffer(void *b) { (void)b; }
void *oidnNewFilter(void *d, const char *type) { (void)d; (void)type; return NULL; }
void oidnSetFilterImage(void *f, const char *name, void *b, int format, size_t w, size_t h, size_t o, size_t ps, size_t rs) {
    (void)f; (void)name; (void)b; (void)format; (void)w; (void)h; (void)o; (void)ps; (void)rs;
}
void oidnSetFilterBool(void *f, const char *name, bool value) { (void)f; (void)name; (void)value; }
void oidnSetFilterInt(void *f, const char *name, int value) { (void)f; (void)name; (void)value; }
void oidnCommitFilter(void *f) { (void)f; }
void oidnExecuteFilter(void *f) { (void)f; }
void oidnReleaseFilter(void *f) { (void)f; }
