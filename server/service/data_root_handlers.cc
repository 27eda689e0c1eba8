// ListDataRoot: the "Server files" browser's listing of --data-root
// (list_data_root.h), for users the users file gives `browse-data-root`.
#include "server/service/list_data_root.h"
#include "server/service/vpm_service.h"

namespace vpm::service {
namespace {

v3::DataRootEntry::Kind KindToProto(DataRootKind kind) {
  switch (kind) {
    case DataRootKind::kFolder:
      return v3::DataRootEntry::FOLDER;
    case DataRootKind::kVolumeFile:
      return v3::DataRootEntry::VOLUME_FILE;
    case DataRootKind::kDicomFolder:
      return v3::DataRootEntry::DICOM_FOLDER;
    case DataRootKind::kArchive:
      return v3::DataRootEntry::ARCHIVE;
    case DataRootKind::kOtherFile:
      return v3::DataRootEntry::OTHER_FILE;
    case DataRootKind::kNotOpenable:
      return v3::DataRootEntry::NOT_OPENABLE;
  }
  return v3::DataRootEntry::KIND_UNSPECIFIED;
}

}  // namespace

grpc::ServerUnaryReactor* VpmService::ListDataRoot(grpc::CallbackServerContext* context,
                                                   const v3::ListDataRootRequest* request,
                                                   v3::ListDataRootResponse* response) {
  return Unary(context, *request, "ListDataRoot", service_->request_pool,
               [=, this](const std::string& user) -> Status {
                 if (!service_->auth->MayBrowseDataRoot(user)) {
                   return absl::PermissionDeniedError(StrCat(
                       "user '", user, "' may not browse the server's files (the users file "
                       "gives that with '", kBrowseDataRootPermission, "')"));
                 }
                 ASSIGN_OR_RETURN(const DataRootListing listing,
                                  service::ListDataRoot(service_->options.data_root,
                                                        request->path()));
                 response->set_path(listing.path);
                 response->set_truncated(listing.truncated);
                 for (const DataRootEntry& e : listing.entries) {
                   v3::DataRootEntry* out = response->add_entries();
                   out->set_name(e.name);
                   out->set_kind(KindToProto(e.kind));
                   out->set_size_bytes(e.size_bytes);
                   out->set_modified_unix_ms(e.modified_unix_ms);
                   out->set_source(e.source);
                 }
                 return absl::OkStatus();
               });
}

}  // namespace vpm::service
