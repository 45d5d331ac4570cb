"""A malformed modelDescription.xml is refused with the element and attribute it lacks."""

import pytest

from orchestrator.errors import FmuError
from orchestrator.model_description import bounds_header, finish_fmi2, to_fmi3

_VARIABLE = ('<ScalarVariable name="x" valueReference="0" causality="output">'
             '<Real min="-1.0" max="2.5"/></ScalarVariable>')


def _description(cosim: str = '<CoSimulation modelIdentifier="m"/>', variable: str = _VARIABLE,
                 structure: str = "") -> str:
    return (f'<fmiModelDescription fmiVersion="2.0" modelName="m" guid="g">{cosim}'
            f"<ModelVariables>{variable}</ModelVariables><ModelStructure>{structure}</ModelStructure>"
            "</fmiModelDescription>")


def test_the_bounds_header_lists_each_declared_range():
    assert "{0u, -1.0, 2.5}, /* x */" in bounds_header(_description())


def test_a_variable_without_a_value_reference_is_named_in_the_bounds_header():
    with pytest.raises(FmuError, match="<ScalarVariable> has no valueReference attribute"):
        bounds_header(_description(variable='<ScalarVariable name="x"><Real min="0"/></ScalarVariable>'))


def test_a_description_without_cosimulation_is_refused_when_its_sources_are_listed():
    with pytest.raises(FmuError, match="<fmiModelDescription> has no <CoSimulation>"):
        finish_fmi2(_description(cosim=""), ["model.c"], "1.0")


def test_an_unknown_without_an_index_is_refused_in_the_fmi3_translation():
    with pytest.raises(FmuError, match="<Unknown> has no index attribute"):
        to_fmi3(_description(structure="<Outputs><Unknown/></Outputs>"), ["model.c"], "1.0")


def test_a_type_without_a_name_is_refused_in_the_fmi3_translation():
    types = '<TypeDefinitions><SimpleType><Real unit="m"/></SimpleType></TypeDefinitions>'
    text = _description().replace("<ModelVariables>", types + "<ModelVariables>")
    with pytest.raises(FmuError, match="<SimpleType> has no name attribute"):
        to_fmi3(text, ["model.c"], "1.0")
