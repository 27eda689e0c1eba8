#include "client/cli/remote_mesh_commands.h"

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "client/common/proto_json.h"
#include "proto/enum_names.h"
#include "client/cli/server_flags.h"
#include "server/common/write_file.h"

namespace vpm::cli {

using nlohmann::json;

namespace {

// What the mesh commands' flags fill.
struct RemoteMeshArgs {
  std::string volume_id, mesh_id, json_out;
  std::vector<int64_t> grid;
  int64_t target = 0;
  std::string tf;
  std::vector<double> point;
  bool geometry = false;
};

// mesh-build (BuildMesh).
void AddMeshBuildCommand(CLI::App& app, const ServerFlags* flags, int* exit_code,
                         std::shared_ptr<RemoteMeshArgs> a) {
  CLI::App* build = app.add_subcommand("mesh-build", "server: BuildMesh");
  build->add_option("--volume-id", a->volume_id)->required();
  build->add_option("--grid", a->grid, "GX GY GZ")->expected(3);
  build->add_option("--target", a->target, "kept vertices (0: 250)");
  build->add_option("--tf", a->tf, "transfer-function preset or v:c,...");
  build->add_option("--refine-at", a->point, "X Y Z mm")->expected(3);
  build->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::BuildMeshRequest request;
    request.set_volume_id(a->volume_id);
    for (int64_t g : a->grid) request.mutable_params()->add_grid(g);
    request.mutable_params()->set_target(a->target);
    request.mutable_params()->set_tf(a->tf);
    if (a->point.size() == 3) {
      auto* p = request.mutable_params()->mutable_refine_at_mm();
      p->set_x(a->point[0]);
      p->set_y(a->point[1]);
      p->set_z(a->point[2]);
    }
    v3::MeshInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().BuildMesh(s.Context().get(), request, &info)));
    PrintJson(MeshJson(info));
    return absl::OkStatus();
  }));
}

// mesh-get (GetMesh), optionally with the geometry as JSON.
void AddMeshGetCommand(CLI::App& app, const ServerFlags* flags, int* exit_code,
                       std::shared_ptr<RemoteMeshArgs> a) {
  CLI::App* get = app.add_subcommand("mesh-get", "server: GetMesh");
  get->add_option("ID", a->mesh_id)->required();
  get->add_flag("--geometry", a->geometry, "include vertices and tets");
  get->add_option("--json", a->json_out, "write the response as JSON here");
  get->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::GetMeshRequest request;
    request.set_mesh_id(a->mesh_id);
    request.set_include_geometry(a->geometry || !a->json_out.empty());
    v3::GetMeshResponse response;
    RETURN_IF_ERROR(FromGrpc(s.stub().GetMesh(s.Context().get(), request, &response)));
    json j = MeshJson(response.info());
    if (!a->json_out.empty()) {
      for (const auto& v : response.vertices()) {
        j["vertices"].push_back({{"position_mm", {v.position_mm().x(), v.position_mm().y(),
                                                  v.position_mm().z()}},
                                 {"kind", std::string(VertexKindName(v.kind()))}, {"hard", v.hard()}});
      }
      for (const auto& t : response.tets()) j["tets"].push_back({t.a(), t.b(), t.c(), t.d()});
      RETURN_IF_ERROR(WriteFile(a->json_out, j.dump() + "\n"));
      std::printf("wrote %s\n", a->json_out.c_str());
    } else {
      PrintJson(j);
    }
    return absl::OkStatus();
  }));
}

// mesh-refine (RefineMesh) and mesh-delete (DeleteMesh).
void AddMeshRefineDeleteCommands(CLI::App& app, const ServerFlags* flags, int* exit_code,
                                 std::shared_ptr<RemoteMeshArgs> a) {
  CLI::App* refine = app.add_subcommand("mesh-refine", "server: RefineMesh (a new mesh)");
  refine->add_option("ID", a->mesh_id)->required();
  refine->add_option("POINT", a->point, "X Y Z mm")->expected(3)->required();
  refine->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::RefineMeshRequest request;
    request.set_mesh_id(a->mesh_id);
    request.mutable_point_mm()->set_x(a->point[0]);
    request.mutable_point_mm()->set_y(a->point[1]);
    request.mutable_point_mm()->set_z(a->point[2]);
    v3::MeshInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().RefineMesh(s.Context().get(), request, &info)));
    PrintJson(MeshJson(info));
    return absl::OkStatus();
  }));
  CLI::App* del = app.add_subcommand("mesh-delete", "server: DeleteMesh (not while a session uses it)");
  del->add_option("ID", a->mesh_id)->required();
  del->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::DeleteMeshRequest request;
    request.set_mesh_id(a->mesh_id);
    v3::DeleteMeshResponse response;
    return FromGrpc(s.stub().DeleteMesh(s.Context().get(), request, &response));
  }));
}

}  // namespace

void AddRemoteMeshCommands(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  auto a = std::make_shared<RemoteMeshArgs>();
  AddMeshBuildCommand(app, flags, exit_code, a);
  AddMeshGetCommand(app, flags, exit_code, a);
  AddMeshRefineDeleteCommands(app, flags, exit_code, a);
}

}  // namespace vpm::cli
