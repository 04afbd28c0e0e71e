#!/bin/bash
# Re-creates each <dataset>/ here from bare clones of the source repositories:
# raw/ = `git show <commit>:<path>`, unmodified; *_recordings.csv = convert_iso230.py.
# MIRRORS: a folder holding <owner>+<name>/repo bare clones (default: /work/.mirror).
# The raw copies are already here: to redo only the conversion, comment out the raw lines.
set -e
cd "$(dirname "$0")"
M=${MIRRORS:-/work/.mirror}
MUTS=$M/anderssandstrom+ecmc_target_muts_logger/repo; MUTS_C=ee350e4c813139fde4608dd0edd331f8d3546028
PSI=$M/paulscherrerinstitute+ecmccfg/repo
GUI=$M/anderssandstrom+ecmccomgui/repo
FIT="reference gain and offset were least-squares fitted to the commanded targets by the ecmc report tool (mainISO230_2.bash): mean offset and linear scale error of the axis are removed from these deviations"
raw() { # git-dir commit path destdir   (copy keeps the repository path under raw/)
  mkdir -p "$4/raw/$(dirname $3)"; git --git-dir=$1 show $2:$3 > "$4/raw/$3"; }
conv() { # dat out source quality instrument prov [axis]
  local ax=""; [ -n "$7" ] && ax="--axis $7"
  python3 convert_iso230.py "$1" $ax --source "$3" --meta "instrument=$5" --meta "provenance=$6" \
     --meta "reference_fit=$FIT" ${4:+--meta "quality=$4"} -o "$2"; }

########## ecmc_target_muts_logger, muts/data/week42_22/xyz  (MUTS target drive unit, 2022-10-19..21)
D=ecmc-muts-week42-xyz; W=muts/data/week42_22
for f in $W/readme.md $W/xyz/readme.md $W/xyz/control_target_x.cfg $W/xyz/control_target_y.cfg $W/xyz/control_target_z.cfg \
         $W/xyz/report_target_x.cfg $W/xyz/report_target_y.cfg $W/xyz/report_target_z_ILD2330_below.cfg \
         $W/xyz/target_x_report_ILD50.md $W/xyz/target_x_report_ILD50.md_ISO230.dat \
         $W/xyz/target_y_report_ILD50.md $W/xyz/target_y_report_ILD50.md_ISO230.dat \
         $W/xyz/target_z_report_ILD2300_below.md $W/xyz/target_z_report_ILD2300_below.md_ISO230.dat; do raw $MUTS $MUTS_C $f $D; done
S="ecmc_target_muts_logger muts/data/week42_22/xyz (ISO 230-2 run of the ESS target drive unit XYZ stage at MUTS, laser triangulation reference)"
P="github.com/anderssandstrom/ecmc_target_muts_logger@$MUTS_C"
conv $D/raw/$W/xyz/target_x_report_ILD50.md_ISO230.dat $D/x_recordings.csv "$S" \
  "re-run of X with another ILD after the first X/Y runs were judged bad (commit 6e53e54 'New test of x with other ILD'); xyz/readme.md:27 'Seems ILD2300-100 is not good.. needs to redo tests with 50mm sensor..'" \
  "Micro-Epsilon ILD2300 (REF_PV IOC_TEST:m0s002-Enc01-PosAct), 2022-10-21" "$P:$W/xyz/target_x_report_ILD50.md_ISO230.dat"
conv $D/raw/$W/xyz/target_y_report_ILD50.md_ISO230.dat $D/y_recordings.csv "$S" \
  "re-run of Y with another ILD after the first X/Y runs were judged bad (commit 866aa7d 'Move x and y tests to back since seems sensor was corrupt..')" \
  "Micro-Epsilon ILD2300 (REF_PV IOC_TEST:m0s002-Enc01-PosAct), 2022-10-21" "$P:$W/xyz/target_y_report_ILD50.md_ISO230.dat"
conv $D/raw/$W/xyz/target_z_report_ILD2300_below.md_ISO230.dat $D/z_recordings.csv "$S" \
  "Z measured with the ILD2300-50mm sensor below (commit d36ab87); readme.md:110 Z zero is 0.6-0.7 mm higher than in the b02 tests" \
  "Micro-Epsilon ILD2300-50mm below the wheel (REF_PV IOC_TEST:m0s011-Enc01-PosAct), 2022-10-20" "$P:$W/xyz/target_z_report_ILD2300_below.md_ISO230.dat"

########## same, xyz/back (runs the engineer set aside: suspected corrupt reference sensor)
D=ecmc-muts-week42-xyz-back; B=$W/xyz/back
for f in $B/report_target_z.cfg $B/target_x_report.md $B/target_x_report.md_ISO230.dat $B/target_x_report_2.md $B/target_x_report_2.md_ISO230.dat \
         $B/target_x_report_8A.md $B/target_x_report_8A.md_ISO230.dat $B/target_y_report.md $B/target_y_report.md_ISO230.dat \
         $B/target_z_report.md $B/target_z_report.md_ISO230.dat $W/readme.md $W/xyz/readme.md; do raw $MUTS $MUTS_C $f $D; done
S="ecmc_target_muts_logger muts/data/week42_22/xyz/back (ISO 230-2 runs set aside by the engineer: reference sensor suspected bad)"
Q="SUSPECT REFERENCE: commit 866aa7d 'Move x and y tests to back since seems sensor was corrupt..'; xyz/readme.md:27 'Seems ILD2300-100 is not good.. needs to redo tests with 50mm sensor..'"
I="Micro-Epsilon ILD2300-100mm (REF_PV IOC_TEST:m0s002-Enc01-PosAct)"
conv $D/raw/$B/target_x_report.md_ISO230.dat   $D/x_recordings.csv    "$S" "$Q" "$I, 2022-10-19" "$P:$B/target_x_report.md_ISO230.dat"
conv $D/raw/$B/target_x_report_2.md_ISO230.dat $D/x_2_recordings.csv  "$S" "$Q; readme.md:98 'Seems axis is slipping.. Test higher current..'" "$I, 2022-10-20" "$P:$B/target_x_report_2.md_ISO230.dat"
conv $D/raw/$B/target_x_report_8A.md_ISO230.dat $D/x_8A_recordings.csv "$S" "$Q; run with higher motor current (commit 61b551a 'Add x test with 8A')" "$I, 2022-10-20" "$P:$B/target_x_report_8A.md_ISO230.dat"
conv $D/raw/$B/target_y_report.md_ISO230.dat   $D/y_recordings.csv    "$S" "$Q" "$I, 2022-10-19" "$P:$B/target_y_report.md_ISO230.dat"
conv $D/raw/$B/target_z_report.md_ISO230.dat   $D/z_recordings.csv    "$S" "SUSPECT: commit 84e6a17 'Add z report (bad)'; replaced by the ILD2300-50mm-below run (d36ab87)" "$I, 2022-10-20" "$P:$B/target_z_report.md_ISO230.dat"

########## paulscherrerinstitute/ecmccfg examples/ESS/mcu1025_fat_sat (ESS MCU1025 test axis, 2021-11-10)
PSI_C=19fd09c5859f97e15cd010927fa0681f2ee81000
D=ecmccfg-mcu1025-fat-sat; E=examples/ESS/mcu1025_fat_sat
for f in $E/readme.md $E/report.cfg $E/control.cfg $E/report.md $E/report.md_ISO230.dat $E/cfg/linear_1.ax; do raw $PSI $PSI_C $f $D; done
git --git-dir=$PSI show $PSI_C:LICENSE > $D/raw/LICENSE
conv $D/raw/$E/report.md_ISO230.dat $D/axis1_recordings.csv \
  "paulscherrerinstitute/ecmccfg examples/ESS/mcu1025_fat_sat (ISO 230-2 run of a linear test axis 'Axis1', laser triangulation reference; axis letter unknown, written as x)" "" \
  "Micro-Epsilon ILD2300 (REF_PV IOC_TEST:m0s012-Enc01-PosAct), 2021-11-10" "github.com/paulscherrerinstitute/ecmccfg@$PSI_C:$E/report.md_ISO230.dat" X

########## BIFROST slit 11358 axis1, tests_2 (ecmccfg branch iso230_eval, qualityControl/data/sampleData.dat)
D=bifrost-slit-11358-axis1; QC=1dc241b744fce3138d5a08fa821f4be1278df2d5
raw $PSI $QC qualityControl/data/sampleData.dat $D; git --git-dir=$PSI show $QC:LICENSE > $D/raw/LICENSE
conv $D/raw/qualityControl/data/sampleData.dat $D/axis1_recordings.csv \
  "paulscherrerinstitute/ecmccfg branch iso230_eval qualityControl/data/sampleData.dat (ISO 230-2 run of BIFROST JJ X-ray slit 11358 axis1, laser triangulation reference; axis letter unknown, written as x)" \
  "file was used as parser test input: some TGT_DATA lines carry extra whitespace (values unchanged)" \
  "Micro-Epsilon ILD2300 (REF_PV IOC_TEST:m0s005-Enc01-PosAct), 2021 (tests_2)" "github.com/paulscherrerinstitute/ecmccfg@$QC:qualityControl/data/sampleData.dat" X

########## BIFROST slit 11360 axis1, tests_2/230_2_3.log (ecmccomgui tools/iso230-2-obsolete)
GUI_C=8488a9991bda72f4f2f7a1b9433db04b6d91d4fc
D=bifrost-slit-11360-axis1; T=tools/iso230-2-obsolete
for f in $T/example_data_ISO230_2.dat $T/example_report_ISO230_2.md $T/readme.md $T/report.md $T/mainISO230_2.bash $T/ecmcISO230_2.py $T/ecmcGetISO230DataFromCAFile.bash $T/ecmcGetDataBeforeTrigg.bash $T/ecmcGearRatioISO230_2.py; do raw $GUI $GUI_C $f $D; done
conv $D/raw/$T/example_data_ISO230_2.dat $D/axis1_recordings.csv \
  "anderssandstrom/ecmccomgui tools/iso230-2-obsolete/example_data_ISO230_2.dat (ISO 230-2 run of BIFROST JJ X-ray slit 11360 axis1, laser triangulation reference; axis letter unknown, written as x)" "" \
  "Micro-Epsilon ILD2300 (REF_PV IOC_TEST:m0s005-Enc01-PosAct), 2021-10 (tests_2/11360/axis1/230_2_3.log)" "github.com/anderssandstrom/ecmccomgui@$GUI_C:$T/example_data_ISO230_2.dat" X
echo done
