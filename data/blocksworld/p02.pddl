(define (problem blocksworld-p02)
  (:domain blocksworld-4ops)
  (:objects
    b1 b2 b3
  )
  (:init
    (on-table b1)
    (on b2 b1)
    (on b3 b2)
    (clear b3)
    (arm-empty)
  )
  (:goal (and
    (on b1 b2)
    (on b2 b3)
  ))
)
