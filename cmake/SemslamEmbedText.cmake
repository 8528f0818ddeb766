# cmake -P script: writes OUTPUT, a C++ source defining `std::string_view NAMESPACE::FUNCTION()` that returns the
# bytes of INPUT (a JavaScript, CSS or other text file kept in a file of its own, embedded at build time).
file(READ ${INPUT} hex HEX)
string(LENGTH "${hex}" hex_length)
math(EXPR size "${hex_length} / 2")
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
string(REGEX REPLACE "(0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,)" "\\1\n" bytes "${bytes}")
file(WRITE ${OUTPUT}.tmp "// Generated from ${INPUT} by cmake/SemslamEmbedText.cmake: do not edit.
#include <string_view>
namespace ${NAMESPACE} {
namespace {
constexpr char kBytes[] = {
${bytes}0};
}  // namespace
std::string_view ${FUNCTION}() { return std::string_view(kBytes, ${size}); }
}  // namespace ${NAMESPACE}
")
file(COPY_FILE ${OUTPUT}.tmp ${OUTPUT} ONLY_IF_DIFFERENT)
file(REMOVE ${OUTPUT}.tmp)
