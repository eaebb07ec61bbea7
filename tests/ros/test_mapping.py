"""The mapping file of --robot ros (htn.ros.mapping), read without ROS: the
names and types it resolves, the goal fields it computes from a skill's
arguments and the world model, and its errors, located in the file."""

from __future__ import annotations

import math
from types import SimpleNamespace as NS

import pytest

from htn.jshop.language.errors import HtnError
from htn.ros import mapping

from conftest import ROOT

FACTS = [
    ("location", ("counter_front", 2.2, 1.5, 0.0)),
    ("location", ("sofa_front", -2.0, 1.5, 90.0)),
]


def test_the_domestic_mapping_drives_through_nav2_and_names_the_rest_by_default():
    m = mapping.read(ROOT / "domains" / "domestic.ros.toml")
    assert (
        mapping.beside(ROOT / "domains" / "domestic.jshop")
        == ROOT / "domains" / "domestic.ros.toml"
    )
    move = m.skill("move_base")
    assert (move.name, move.type) == ("/navigate_to_pose", "nav2_msgs/action/NavigateToPose")
    values = move.values(("sofa_front",), FACTS)
    assert values["pose.pose.position.x"] == -2.0 and values["pose.header.frame_id"] == "map"
    q = values["pose.pose.orientation"]
    assert q["z"] == pytest.approx(math.sin(math.pi / 4)) and q["w"] == pytest.approx(
        math.cos(math.pi / 4)
    )
    grasp, on = m.skill("grasp"), m.check("on")
    assert (grasp.name, grasp.type) == ("/robot/skill/grasp", "htn_interfaces/action/Skill")
    assert (on.name, on.type) == ("/robot/check/on", "htn_interfaces/srv/Check")
    assert on.values(("pringles", "sofa"), []) == {"args": ["pringles", "sofa"]}
    assert m.wait == 5.0 and m.full("observe") == "/robot/observe"


def test_fill_sets_dotted_fields_converting_to_the_fields_types():
    goal = NS(
        pose=NS(
            header=NS(frame_id=""),
            pose=NS(position=NS(x=0.0, y=0.0), orientation=NS(x=0.0, y=0.0, z=0.0, w=1.0)),
        ),
        count=0,
        args=[],
        on=False,
    )
    mapping.fill(
        goal,
        {
            "pose.pose.position.x": "2.5",
            "count": 3.0,
            "args": ["a", 1],
            "on": "true",
            "pose.pose.orientation": {"z": 1.0, "w": 0.0},
        },
    )
    assert goal.pose.pose.position.x == 2.5 and goal.count == 3 and isinstance(goal.count, int)
    assert goal.args == ["a", "1"] and goal.on is True and goal.pose.pose.orientation.z == 1.0
    with pytest.raises(HtnError, match="has no field 'posse'"):
        mapping.fill(goal, {"posse.x": 1})
    with pytest.raises(HtnError, match="cannot set 'count'"):
        mapping.fill(goal, {"count": "many"})


def test_a_place_the_world_model_does_not_know_fails_the_skill_with_the_pattern():
    m = mapping.read(ROOT / "domains" / "domestic.ros.toml")
    with pytest.raises(HtnError, match=r"no fact of the world model matches \(location moon \?x"):
        m.skill("move_base").values(("moon",), FACTS)


def test_a_topic_check(tmp_path):
    f = tmp_path / "robot.ros.toml"
    f.write_text(
        '[checks.no_collision]\ntopic = "bumper"\ntype = "std_msgs/msg/Bool"\n'
        'field = "data"\nequals = false\n'
    )
    check = mapping.read(f).check("no_collision")
    assert check.is_topic and check.name == "/robot/bumper"
    assert (check.field_name, check.equals) == ("data", False)


@pytest.mark.parametrize(
    "text, where",
    [
        ("namespace = '/r'\nspeed = 3\n", ":2: unknown key 'speed'"),
        ("[skills.grasp\naction = 'x'\n", ":1:14: not TOML"),
        ("wait = -1\n", ":1: 'wait' must be a number of seconds"),
        ("[skills.grasp]\naction = 'g'\nkind = 'x'\n", ":3: [skills.grasp]: unknown key 'kind'"),
        (
            "[skills.grasp]\ntype = 'htn_interfaces/srv/Check'\n",
            ":1: [skills.grasp]: type 'htn_interfaces/srv/Check' is not an action",
        ),
        (
            "[checks.on]\ntype = 'std_msgs/msg/Bool'\n",
            ":1: [checks.on]: type 'std_msgs/msg/Bool' is not a service (a check is a service or a topic)",
        ),
        ("[skills.grasp]\ntype = 'Check'\n", "is not a ROS type name"),
        ("[checks.on]\ntopic = 'x'\ntype = 'std_msgs/msg/Bool'\n", "needs 'field'"),
        ("[checks.on]\nservice = 's'\ntopic = 't'\n", "a service or a topic, not both"),
        ("[skills.go]\nwhere = 'location $1'\n", "'where' must be one atom"),
        ("[skills.go]\n[skills.go.goal]\n'pose..x' = 1\n", "is not a field path"),
    ],
)
def test_mistakes_in_the_mapping_file_are_located_errors(tmp_path, text, where):
    f = tmp_path / "bad.ros.toml"
    f.write_text(text)
    with pytest.raises(HtnError) as error:
        mapping.read(f)
    assert str(error.value).startswith(str(f)) and where in str(error.value), str(error.value)


def test_a_missing_mapping_file_is_one_error(tmp_path):
    with pytest.raises(HtnError, match="cannot read the mapping file"):
        mapping.read(tmp_path / "none.ros.toml")
    assert mapping.beside(tmp_path / "d.jshop") is None
