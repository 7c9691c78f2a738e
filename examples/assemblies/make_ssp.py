"""Package an assembly FMU as an SSP (System Structure and Parameterization 1.0): the FMU as the
one component of the system, the outputs named on the command line as its connectors, the
FMU's default experiment as the system's. Any SSP tool (FMPy's simulate_ssp, OMSimulator) then
runs the whole machine from one file.

Run: python examples/assemblies/make_ssp.py DoublePendulum.fmu -o DoublePendulum.ssp \\
         --output 'lower.tip.r[1]' --output 'lower.tip.r[3]' --output elbow.angle"""

from __future__ import annotations

import argparse
import sys
import zipfile
from pathlib import Path
from xml.sax.saxutils import quoteattr

from fmpy import read_model_description


def system_structure(fmu: Path, outputs: list[str]) -> str:
    md = read_model_description(str(fmu))
    known = {v.name: v for v in md.modelVariables}
    for name in outputs:
        if name not in known:
            raise SystemExit(f"{fmu}: no variable '{name}'")
        if known[name].causality != "output":
            raise SystemExit(f"{fmu}: '{name}' is {known[name].causality}, not an output")
    experiment = md.defaultExperiment
    connectors = "\n".join(
        f'          <ssd:Connector name={quoteattr(n)} kind="output"><ssc:Real/></ssd:Connector>' for n in outputs)
    stop = experiment.stopTime if experiment and experiment.stopTime else 1.0
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" version="1.0" name={quoteattr(md.modelName)}>
  <ssd:System name="Root">
    <ssd:Elements>
      <ssd:Component name="assembly" source="resources/{fmu.name}" type="application/x-fmu-sharedlibrary">
        <ssd:Connectors>
{connectors}
        </ssd:Connectors>
      </ssd:Component>
    </ssd:Elements>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0.0" stopTime="{stop}"/>
</ssd:SystemStructureDescription>
"""


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("fmu", type=Path)
    p.add_argument("-o", "--output-file", type=Path, required=True, help="the .ssp to write (never the FMU)")
    p.add_argument("--output", action="append", default=[], help="an output of the FMU to expose (repeat)")
    args = p.parse_args(argv)
    if not args.output:
        p.error("name at least one --output")
    if args.output_file.resolve() == args.fmu.resolve():
        p.error("the SSP would replace the FMU")
    ssd = system_structure(args.fmu, args.output)
    with zipfile.ZipFile(args.output_file, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", ssd)
        z.write(args.fmu, f"resources/{args.fmu.name}")
    print(f"wrote {args.output_file}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
