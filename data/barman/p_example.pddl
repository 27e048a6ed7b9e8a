(define (problem barman-p-example)
  (:domain barman)
  (:objects
    left right - hand
    shaker1 shaker2 shaker3 - shaker
    shot1 shot2 - shot
    ingredient1 ingredient2 ingredient3 - ingredient
    cocktail1 - cocktail
    dispenser1 dispenser2 dispenser3 - dispenser
    l0 l1 l2 - level
  )
  (:init
    (handempty left)
    (handempty right)
    (ontable shaker1)
    (clean shaker1)
    (empty shaker1)
    (ontable shaker2)
    (clean shaker2)
    (empty shaker2)
    (ontable shaker3)
    (clean shaker3)
    (empty shaker3)
    (ontable shot1)
    (clean shot1)
    (empty shot1)
    (ontable shot2)
    (clean shot2)
    (empty shot2)
    (shaker-empty-level shaker1 l0)
    (shaker-level shaker1 l0)
    (shaker-empty-level shaker2 l0)
    (shaker-level shaker2 l0)
    (shaker-empty-level shaker3 l0)
    (shaker-level shaker3 l0)
    (next l0 l1)
    (next l1 l2)
    (dispenses dispenser1 ingredient1)
    (dispenses dispenser2 ingredient2)
    (dispenses dispenser3 ingredient3)
    (cocktail-part1 cocktail1 ingredient3)
    (cocktail-part2 cocktail1 ingredient1)
  )
  (:goal (and
    (contains shot1 cocktail1)
  ))
)
