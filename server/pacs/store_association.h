// One association that a node opened with vpm's DICOM listener: C-ECHO,
// and C-STORE of images, each checked and kept in the association's own
// temporary folder (or handed to the C-MOVE that asked for it). When the
// association is released its series enter the received store whole; an
// aborted association, or a series with a refused instance, keeps nothing.
// Runs on a listener thread (dicom_listener.h); nothing here throws.
#pragma once

#include <dcmtk/config/osconfig.h>  // first among DCMTK headers
#include <dcmtk/dcmnet/scpthrd.h>

#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <memory>
#include <string>

#include "server/pacs/move_registry.h"
#include "server/pacs/received_store.h"

namespace vpm::pacs {

// What happened to one series of an association (the audit's "receive").
struct ReceiveReport {
  std::string calling_ae;
  std::string study_uid;
  std::string series_uid;
  int64_t instances = 0;  // kept
  int64_t refused = 0;    // instances answered with a failure status
  Status result;
};

class StoreAssociation : public DcmThreadSCP {
 public:
  struct Context {
    std::string ae_title;             // the listener's: the called AE title must be it
    bool loopback_only = false;       // refuse peers that are not 127.0.0.0/8
    int64_t max_instance_bytes = 0;   // one instance, bytes
    ReceivedStore* store = nullptr;
    MoveRegistry* moves = nullptr;
    // vpm's own calling AE titles of "move" endpoints: a C-STORE that a
    // C-MOVE of theirs caused but no retrieval expects (cancelled, timed
    // out) is refused, never put in the received store.
    std::set<std::string> own_move_originators;
    std::function<void(const ReceiveReport&)> report;
    std::function<void()> on_end;  // the association is over (before its socket closes)
  };
  StoreAssociation(Context context, int socket);

 protected:
  OFBool checkCalledAETitleAccepted(const OFString& called_ae) override;
  void notifyAssociationRequest(const T_ASC_Parameters& params,
                                DcmSCPActionType& action) override;
  OFCondition handleIncomingCommand(T_DIMSE_Message* message,
                                    const DcmPresentationContextInfo& context) override;
  void notifyRECEIVEProgress(unsigned long bytes) override;
  void notifyReleaseRequest() override { released_ = true; }
  void notifyAssociationTermination() override;

 private:
  struct SeriesState {
    ReceivedStore::SeriesFiles files;
    Status failure;
    int64_t refused = 0;
  };
  // The DIMSE status of one received file (0: kept).
  Uint16 Keep(const std::string& path, const T_DIMSE_C_StoreRQ& request);
  Uint16 KeepForStore(const std::string& path, int64_t bytes, const ReceivedInstance& instance);

  Context context_;
  int socket_;
  std::string calling_ae_;
  bool released_ = false;
  bool over_cap_ = false;
  int64_t received_ = 0;
  std::unique_ptr<ReceivedStore::Incoming> incoming_;
  std::map<std::string, SeriesState> series_;  // by series UID
};

}  // namespace vpm::pacs
