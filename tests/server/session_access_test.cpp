// The control id and the read-only view id (issue 14.7): view holders receive the session's
// frames and messages, under the view id only, and cannot change the session; every subscriber
// learns of versions made by others.
#include <gtest/gtest.h>

#include "service_fixture.h"

namespace isomesh::server {
namespace {

using protocol::Access;
using protocol::ErrorCode;
using namespace testing;

/// Every session id `connection` received, in messages and frame headers.
std::set<protocol::SessionId> ids_received(const TestConnection& connection) {
    std::set<protocol::SessionId> ids;
    for (const auto& m : connection.messages) {
        std::visit(
            [&](const auto& message) {
                if constexpr (requires { message.session; }) {
                    if constexpr (requires { *message.session; }) {
                        if (message.session) ids.insert(*message.session);
                    } else {
                        ids.insert(message.session);
                    }
                }
                if constexpr (requires { message.view; }) {
                    if (message.view) ids.insert(*message.view);
                }
            },
            m);
    }
    for (const auto& frame : connection.frames) ids.insert(frame.session);
    return ids;
}

TEST(MeshService, view_id_follows_the_session_read_only) {
    Fixture f;
    TestConnection a(f.service), b(f.service);
    const auto control = create(a, create_request("x^2+y^2+z^2=a", 3000, {{"a", 4.0}}, 1));
    const auto* created = created_reply(a, 1);
    ASSERT_TRUE(created && created->view && created->access == Access::control);
    const protocol::SessionId view = *created->view;
    EXPECT_NE(view, control);

    ASSERT_TRUE(request(b, protocol::Subscribe{2, view}, 2));
    const auto* subscribed = b.find<protocol::Subscribed>(protocol::RequestId{2});
    ASSERT_NE(subscribed, nullptr);
    EXPECT_EQ(subscribed->session, view);
    EXPECT_EQ(subscribed->access, Access::view);
    EXPECT_FALSE(subscribed->view);
    ASSERT_TRUE(wait_converged(a, control));
    ASSERT_TRUE(wait_converged(b, view));
    EXPECT_EQ(canonical_triangles(b.replicas[view]), canonical_triangles(a.replicas[control]));

    // Read-only: every request that changes the session is refused, naming the view id.
    protocol::Update update;
    update.id = 3;
    update.session = view;
    update.parameters = protocol::Parameters{{"a", 5.0}};
    const std::pair<std::int64_t, protocol::ClientMessage> refused[] = {
        {3, update},
        {4, protocol::Pause{4, view}},
        {5, protocol::Resume{5, view}},
        {6, protocol::Close{6, view}},
    };
    for (const auto& [id, message] : refused) {
        ASSERT_TRUE(request(b, message, id));
        ASSERT_NE(error_for(b, id), nullptr) << id;
        EXPECT_EQ(error_for(b, id)->code, ErrorCode::read_only) << id;
        EXPECT_EQ(error_for(b, id)->session, view);
    }
    EXPECT_EQ(f.service.find(control)->latest().state.version, 1u);

    // What a view holder may do: resync and unsubscribe.
    const std::size_t frames = b.frames.size();
    ASSERT_TRUE(request(b, protocol::Resync{7, view}, 7));
    ASSERT_TRUE(b.wait_for([&] { return b.frames.size() > frames; }));
    EXPECT_TRUE(b.frames.back().flags & protocol::frame_flags::catch_up);
    ASSERT_TRUE(request(b, protocol::Unsubscribe{8, view}, 8));
    EXPECT_NE(b.find<protocol::Ack>(protocol::RequestId{8}), nullptr);

    EXPECT_EQ(ids_received(b), std::set<protocol::SessionId>{view});  // never the control id
    EXPECT_EQ(ids_received(a), (std::set<protocol::SessionId>{control, view}));
}

TEST(MeshService, subscribers_learn_of_versions_made_by_other_controllers) {
    Fixture f;
    TestConnection creator(f.service), controller(f.service), viewer(f.service);
    const auto control = create(creator, create_request("x^2+y^2+z^2=a", 2000, {{"a", 4.0}}, 1));
    const protocol::SessionId view = *created_reply(creator, 1)->view;
    ASSERT_TRUE(request(controller, protocol::Subscribe{2, control}, 2));
    ASSERT_TRUE(request(viewer, protocol::Subscribe{3, view}, 3));

    protocol::Update update;
    update.id = 4;
    update.session = control;
    update.parameters = protocol::Parameters{{"a", 5.0}};
    update.box = protocol::Box{-4, 4, -4, 4, -4, 4};
    ASSERT_TRUE(request(controller, update, 4));
    ASSERT_NE(controller.find<protocol::Updated>(protocol::RequestId{4}), nullptr);

    const auto told = [](TestConnection& c) -> const protocol::Updated* {
        c.wait_for([&] { return c.find<protocol::Updated>(std::nullopt) != nullptr; }, 5);
        return c.find<protocol::Updated>(std::nullopt);
    };
    const protocol::Updated* to_creator = told(creator);
    ASSERT_NE(to_creator, nullptr);
    EXPECT_FALSE(to_creator->id);
    EXPECT_EQ(to_creator->session, control);
    EXPECT_EQ(to_creator->view, view);
    EXPECT_EQ(to_creator->state.version, 2u);
    EXPECT_EQ(to_creator->state.parameters.at("a"), 5.0);
    EXPECT_EQ(to_creator->state.box, (protocol::Box{-4, 4, -4, 4, -4, 4}));
    const protocol::Updated* to_viewer = told(viewer);
    ASSERT_NE(to_viewer, nullptr);
    EXPECT_EQ(to_viewer->session, view);
    EXPECT_FALSE(to_viewer->view);
    EXPECT_EQ(to_viewer->access, Access::view);
    EXPECT_EQ(controller.count<protocol::Updated>(), 1u);  // its reply only
    EXPECT_TRUE(wait_converged(creator, control, 2));
    EXPECT_TRUE(wait_converged(viewer, view, 2));
}

}  // namespace
}  // namespace isomesh::server
