#include "server/service/request_limits.h"

#include <string>
#include <vector>

#include <google/protobuf/descriptor.h>

namespace vpm::service {
namespace {

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;

size_t LimitFor(const FieldDescriptor& field) {
  if (field.name() == "text") return kMaxTextBytes;
  if (field.name().ends_with("_id")) return kMaxIdBytes;
  return kMaxStringBytes;
}

Status CheckString(const std::string& value, const FieldDescriptor& field,
                   const std::string& where) {
  const size_t limit = LimitFor(field);
  if (value.size() <= limit) return absl::OkStatus();
  return absl::InvalidArgumentError(
      StrCat(where, ": ", value.size(), " bytes; at most ", limit));
}

// Nested messages are at most a few levels deep in vpm.proto; `depth` stops a
// pathological one all the same.
Status CheckMessage(const Message& message, const std::string& prefix, int depth) {
  if (depth > 16) return absl::InvalidArgumentError(StrCat(prefix, ": nested too deeply"));
  const auto* reflection = message.GetReflection();
  std::vector<const FieldDescriptor*> fields;
  reflection->ListFields(message, &fields);  // only the fields that are set
  for (const FieldDescriptor* field : fields) {
    const std::string name = prefix.empty() ? std::string(field->name())
                                            : StrCat(prefix, ".", field->name());
    const bool is_string = field->type() == FieldDescriptor::TYPE_STRING;
    const bool is_message = field->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE;
    if (!is_string && !is_message) continue;
    if (!field->is_repeated()) {
      RETURN_IF_ERROR(is_string
                          ? CheckString(reflection->GetString(message, field), *field, name)
                          : CheckMessage(reflection->GetMessage(message, field), name, depth + 1));
      continue;
    }
    const int count = reflection->FieldSize(message, field);
    for (int i = 0; i < count; ++i) {
      const std::string item = StrCat(name, "[", i, "]");
      RETURN_IF_ERROR(
          is_string ? CheckString(reflection->GetRepeatedString(message, field, i), *field, item)
                    : CheckMessage(reflection->GetRepeatedMessage(message, field, i), item,
                                   depth + 1));
    }
  }
  return absl::OkStatus();
}

}  // namespace

Status CheckRequestLimits(const google::protobuf::Message& request) {
  return CheckMessage(request, "", 0);
}

}  // namespace vpm::service
