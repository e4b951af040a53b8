# The kinds of scene the fast engine is measured on, against the plain `bench`
# cloth (sourced by engine_scenes.sh and instructions.sh).
#
# name | scene and settings (the grid size is added; the first case is the bench the
# others are measured against). The bench moved 300 m off the origin is the same
# cloth, on fixed-point positions (`grid-mixed`), which the drape and the sheet
# need: what that precision costs by itself. The sheet's last two cases part its
# cost: with its limit at 100 every spring is measured and none corrected, and
# without it there is no pass after the step.
CASES=(
  "bench (plain)|--scene bench"
  "bench, fixed-point positions|--scene bench --set origin=300,1,0"
  "drape (sphere, ground, friction)|--scene drape --set self_collision=false"
  "drape + self-collision|--scene drape"
  "50 pins at random places|--scene bench --set pins=RANDOM50"
  "air damping|--scene bench --set air_damping=0.0001"
  "bench-wind (drag)|--scene bench-wind"
  "  + Verlet|--scene bench-wind --set integrator=\"verlet\""
  "  + Verlet, 10% stretch limit (sheet)|--scene bench-wind --set integrator=\"verlet\" --set stretch_limit=0.1 --set gust=1"
  "sheet (the scene itself)|--scene sheet"
  "  sheet, limit never reached (at 100)|--scene sheet --set stretch_limit=100"
  "  sheet without its limit|--scene sheet --set stretch_limit=none"
)

# The arguments of case $1 on an $2 x $2 grid: the 50 random pins drawn for the size.
case_args() {
  local args=${CASES[$1]#*|}
  if [[ $args == *RANDOM50* ]]; then
    local pins
    pins=$(python3 -c "import random; r=random.Random(7); print('[' + ','.join(str(i) for i in sorted(r.sample(range($2*$2), 50))) + ']')")
    args=${args/RANDOM50/$pins}
  fi
  echo "$args"
}
