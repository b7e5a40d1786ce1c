// Linked into the test programs that load the vendor OpenNI2 libraries, in the AddressSanitizer
// build only: those libraries have no frame pointers, so their leak stacks are unwound in full
// (the fast unwinder stops at their first frame, before the frame that names the library, and
// test/lsan.supp suppresses by library name). The suite's ASAN_OPTIONS set no unwinder, so this
// default stands; the rest of the suite keeps the fast one (a full unwind at every allocation
// costs a program linking OpenCV 0.5 s at its start alone).
extern "C" const char* __asan_default_options() { return "fast_unwind_on_malloc=0"; }
